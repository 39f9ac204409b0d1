// Data preparation, first half (paper §4.1): make the input a clean manifold surface.
#pragma once
#include <cstddef>
#include <utility>
#include <vector>

#include "core/stage_stats.hpp"
#include "core/surface.hpp"

namespace tightex {

/// Makes the input a clean manifold surface (paper §4.1), in six steps: welds vertices with bit-equal
/// positions within each source mesh (TexturedMesh::source_mesh), drops zero-area triangles, sets
/// aside exact repeats (the same corners in the same cyclic order, texture coordinates and material as
/// an earlier triangle of the same source mesh; `repeats`, if given, gets each as (repeat, the
/// triangle it repeats), sorted) and the triangles `left_out` marks (if given; per input triangle),
/// gives each copy of a surface with other texture coordinates or material vertices of its own, orients each connected patch consistently
/// (the orientation most of its area has), pairs the halfedges of every edge used by exactly two triangles in opposite directions (every
/// other edge is sliced: non-manifold edges, and edges whose two triangles still disagree on orientation, so a Mobius strip becomes an
/// orientable strip), slices non-manifold vertices, and closes the slits slicing left inside one sheet. Requires: nothing of the mesh (any
/// triangle soup; indices in range, as the readers guarantee). Guarantees: a manifold surface (`opposite` built) holding every triangle
/// with area that is neither set aside as a repeat nor left out; face_parent and input_face map to input triangles, vertex_parent to input
/// vertices, and input_corner gives each corner's input corner (a reoriented triangle has its corners 1 and 2 swapped). `stats`, if given,
/// gets what each step did. Throws: nothing of its own.
Surface prepare_surface(const TexturedMesh& mesh, RepairStats* stats, std::vector<std::pair<uint32_t, uint32_t>>* repeats = nullptr,
                        const std::vector<char>* left_out = nullptr);

}  // namespace tightex
