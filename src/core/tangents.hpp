// Tangent frames of tangent-space normal maps, compatible with MikkTSpace (the convention glTF names for
// a primitive without TANGENT): per corner, the direction of increasing u projected onto the plane of
// the corner's normal, averaged over the corners that share a vertex, normal, texture coordinate and
// handedness, weighted by each corner's angle; the handedness from the sign of the triangle's area in
// texture space. Written from the published description, not from its source.
#pragma once
#include <vector>

#include "core/mesh.hpp"

namespace tightex {

/// The normal of the tangent frame at corner k of triangle t: the corner's normal when the mesh has one
/// (finite, non-zero), else the triangle's geometric normal (glTF's flat normals); normalised; (0, 0, 1)
/// for a triangle without area and no normal.
Vec3 frame_normal(const TexturedMesh& mesh, size_t t, int k);

/// The tangent of every corner (TexturedMesh::corner_tangent's layout) from the positions, frame
/// normals and the texture coordinates a renderer samples (TexturedMesh::sampled_uv).
/// Guarantees: 3 per triangle; xyz of unit length and orthogonal to frame_normal; w = +1 or -1. A
/// corner whose triangle has no area in texture space gets the average of its vertex group, or any
/// unit vector orthogonal to its normal when the whole group is degenerate. Deterministic.
std::vector<Vec4> compute_corner_tangents(const TexturedMesh& mesh);

/// mesh.corner_tangent made complete: computed when it is empty, and where a corner's tangent is not
/// usable (zero, non-finite, or w not +-1: a primitive without TANGENT beside one with) the computed
/// one; usable tangents orthonormalised against frame_normal, w made exactly +-1.
std::vector<Vec4> completed_corner_tangents(const TexturedMesh& mesh);

}  // namespace tightex
