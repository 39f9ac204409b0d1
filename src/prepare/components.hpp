// Data preparation (paper §4.1): the prepared surface split into its connected components, each of
// which becomes one chart.
#pragma once
#include <vector>

#include "core/surface.hpp"

namespace tightex {

/// Splits a manifold surface into its connected components (through shared edges), ordered by first
/// triangle. Paper §4.1.
/// Requires: `s.opposite` built (prepare_surface's output or any stage after it).
/// Guarantees: each component has local indices; vertex_parent / face_parent map into `s`; the input
/// map is inherited from `s`; every triangle of `s` is in exactly one component.
/// Throws: nothing.
std::vector<Surface> split_components(const Surface& s);

}  // namespace tightex
