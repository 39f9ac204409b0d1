#include "pipeline/plan_report.hpp"

#include <algorithm>
#include <numeric>
#include <string>

namespace tightex {

namespace {

/// Components listed one by one: the largest by triangles, and besides them every one that fell back
/// or kept its UVs (up to as many again); the totals over all components are in "preparation".
constexpr size_t kReportComponents = 256;

std::vector<char> listed_components(const Plan::State& plan, const std::vector<CutStats>& cuts) {
  const size_t nc = plan.components.size();
  std::vector<char> listed(nc, 0);
  std::vector<size_t> order(nc);
  std::iota(order.begin(), order.end(), size_t(0));
  auto larger = [&](size_t a, size_t b) {
    const size_t fa = plan.components[a].num_faces(), fb = plan.components[b].num_faces();
    return fa != fb ? fa > fb : a < b;
  };
  const size_t top = std::min(nc, kReportComponents);
  std::partial_sort(order.begin(), order.begin() + std::ptrdiff_t(top), order.end(), larger);
  for (size_t k = 0; k < top; ++k) listed[order[k]] = 1;
  size_t troubled = 0;
  for (size_t c = 0; c < nc && troubled < kReportComponents; ++c)
    if (!listed[c] && (!cuts[c].fallback_reason.empty() || !plan.kept[c].empty())) listed[c] = 1, ++troubled;
  return listed;
}

void add_totals(const Plan::State& plan, const std::vector<CutStats>& cuts, Preparation& p) {
  p.components = plan.components.size();
  for (const CutStats& cs : cuts) {
    p.holes_filled += cs.holes_filled;
    p.components_longest_hole_capped += cs.longest_loop_capped;
    p.holes_cut += cs.holes_cut;
    p.components_with_fallback += !cs.fallback_reason.empty();
  }
  p.components_kept_original_uvs =
      size_t(std::count_if(plan.kept.begin(), plan.kept.end(), [](const std::string& k) { return !k.empty(); }));
}

}  // namespace

void fill_plan_report(const TexturedMesh& input, const Plan::State& plan, const std::vector<double>& areas,
                      const std::vector<CutStats>& cuts, const std::vector<SquareMapStats>& maps, ReportData& report) {
  report.input = {input.source, input.num_vertices(), input.num_triangles(), input.materials.size(), input.textures.size(), std::nullopt};
  add_totals(plan, cuts, report.preparation);
  const std::vector<char> listed = listed_components(plan, cuts);
  for (size_t c = 0; c < plan.components.size(); ++c)
    if (listed[c])
      report.components.push_back({c, plan.components[c].num_faces(), areas[c], cuts[c], maps[c], plan.kept[c], plan.rects[c]});
}

}  // namespace tightex
