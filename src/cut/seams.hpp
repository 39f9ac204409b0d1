// The input's texture seams, mapped onto a component's edges: the cut stages prefer them.
#pragma once
#include <vector>

#include "core/mesh.hpp"
#include "core/surface.hpp"

namespace tightex {

/// The input's texture seams along a component's edges: per halfedge (3 * face + corner) of
/// `component`, 1 where the two input triangles at that edge disagree on the texture coordinate of
/// either endpoint or on the material, 0 elsewhere and on the boundary (both halfedges of an edge
/// agree). The cut stages prefer these edges (kSeamCost in cut/graph.hpp): a new seam there is where
/// the eye already accepts a discontinuity.
/// Requires: the component's input map (Surface::input_face / input_corner) pointing into `input`.
/// Throws: nothing.
std::vector<char> find_texture_seams(const TexturedMesh& input, const Surface& component);

}  // namespace tightex
