// The library's entry check on a mesh built in code (read_obj guarantees all of it).
#pragma once
#include "core/mesh.hpp"

namespace tightex {

/// Throws InputError naming the element where `mesh` has no triangle, a non-finite coordinate, an index
/// out of range, or not three texture coordinates per triangle.
void validate_mesh(const TexturedMesh& mesh);

}  // namespace tightex
