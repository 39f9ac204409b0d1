// An input that is already what tightex makes: every surface one chart, its texture used throughout
// (tightex's own output, a quad that fills its image). Mapping it again could only resample it, so it
// is kept as it came.
#pragma once
#include <string>
#include <vector>

#include "core/surface.hpp"
#include "pipeline/plan_state.hpp"
#include "tightex/options.hpp"

namespace tightex {

/// Texel utilization from which an input of one chart per component counts as filling its texture:
/// tightex's own output uses 99.7-100% (the texel centres along its charts' outer edges).
constexpr double kTightUtilization = 0.99;

/// The texel utilization (docs/metrics.md's) of `input` where every component's triangles sample an image
/// (its pixels loaded or not yet) through coordinates continuous across every interior edge (one chart, one material) and the
/// images are at least kTightUtilization used; 0 otherwise.
double tight_utilization(const TexturedMesh& input, const std::vector<Surface>& components);

/// Why every component is to be kept with its own texture coordinates and images, for an input of
/// tight_utilization `utilization`; "" where it is to be mapped: kept only with the default budget and
/// the atlas layout (a budget or layout asked for is a request to map).
std::string keep_tight_reason(double utilization, const Options& options, const TextureBudget& budget);

}  // namespace tightex
