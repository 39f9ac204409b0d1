// Data preparation (paper §4.1): holes capped with scaffolding.
#pragma once
#include <vector>

#include "core/surface.hpp"

namespace tightex {

/// Closes the given boundary loops with the §4.1 centroid fan: one new vertex at the loop's centroid,
/// one triangle per loop edge.
/// Requires: `loops` are boundary loops of `s` (halfedge sequences from boundary_loops), each at most
/// once.
/// Guarantees: the original vertices and triangles keep their ids (vertex_parent / face_parent are the
/// identity there); new vertices have vertex_parent = kNone and new triangles face_parent = kNone: they
/// are scaffolding, never output. The input map is inherited from `s`.
/// Throws: InternalError if the capped surface is not manifold (build_opposite), which loops of `s`
/// cannot cause.
Surface fill_holes(const Surface& s, const std::vector<std::vector<uint32_t>>& loops);

}  // namespace tightex
