// Cutting a surface open along a set of its edges (paper §4.2): the cut graph becomes the disk's boundary.
#pragma once
#include <vector>

#include "core/graph.hpp"
#include "core/surface.hpp"

namespace tightex {

/// Cuts `s` open along the given edges, geometry-central's cutAlongEdges: every vertex splits into one
/// copy per fan of corners that stays connected through uncut edges (group_corners).
/// Requires: `s` manifold, `g` = EdgeGraph(s), `cut_edge` one flag per edge of `g`.
/// Guarantees: the same triangles in the same order and corner order; vertex_parent maps each new
/// vertex to the vertex of `s` it is a copy of, face_parent is the identity; `opposite` is rebuilt
/// (a cut edge becomes two boundary edges); the input map is inherited from `s`.
/// Throws: nothing.
Surface cut_along_edges(const Surface& s, const EdgeGraph& g, const std::vector<char>& cut_edge);

}  // namespace tightex
