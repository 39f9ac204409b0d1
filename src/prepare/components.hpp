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

/// Splits a component into `parts` pieces, each a connected surface of its own (so each becomes a
/// chart): geodesic Voronoi regions of seeds spread by farthest-point sampling (compact, about equal
/// where the surface is even), their borders smoothed so that no face has two edges on one (it would be
/// an ear squeezed flat on the square's side), islands joined to the neighbour they share most edges
/// with; vertices on a border get one copy per piece. For a page cap (Options::max_page_side) that one
/// component's texels exceed.
/// Requires: `component` manifold and connected with `opposite` built (an element of split_components);
/// parts >= 1.
/// Guarantees: every triangle of `component` is in exactly one piece; at most `parts` pieces;
/// face_parent / vertex_parent map into `component`; the input map is inherited.
/// Throws: nothing but std::bad_alloc.
std::vector<Surface> split_into_parts(const Surface& component, int parts);

}  // namespace tightex
