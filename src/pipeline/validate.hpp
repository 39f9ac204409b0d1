// The library's entry check on a mesh built in code (read_obj guarantees all of it).
#pragma once
#include "core/mesh.hpp"

namespace tightex {

/// Throws InputError naming the element where `mesh` has no triangle, a non-finite coordinate, an index
/// out of range (a material's texture or map included), not three texture coordinates per triangle, or
/// corner tangents neither absent nor three per triangle.
void validate_mesh(const TexturedMesh& mesh);

}  // namespace tightex
