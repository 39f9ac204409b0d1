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

/// Why `input`'s components are all to be kept with their own texture coordinates and images; "" where
/// it is to be mapped. Kept only with the default budget and the atlas layout (a budget or layout asked
/// for is a request to map), where every component's triangles sample an image through coordinates
/// continuous across every interior edge (one chart, one material), and the images are at least
/// kTightUtilization used (METRICS.md's utilization).
std::string already_tight(const TexturedMesh& input, const Options& options, const TextureBudget& budget,
                          const std::vector<Surface>& components);

}  // namespace tightex
