// The plan's part of the typed report (report/report.hpp): preparation totals and an entry per
// listed component (the largest, and every one that fell back or kept its UVs).
#pragma once
#include <vector>

#include "pipeline/plan_state.hpp"
#include "report/report.hpp"

namespace tightex {

/// Fills report.input, report.preparation and report.components from the plan's components, their
/// 3D areas, cuts and maps (per component, in plan order).
void fill_plan_report(const TexturedMesh& input, const Plan::State& plan, const std::vector<double>& areas,
                      const std::vector<CutStats>& cuts, const std::vector<SquareMapStats>& maps, ReportData& report);

}  // namespace tightex
