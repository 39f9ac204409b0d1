// Writing the result: OBJ + MTL + texture images, atomically.
#pragma once
#include <string>

#include "core/mesh.hpp"
#include "io/image_io.hpp"

namespace tightex {

/// Writes OUTDIR/<name>.obj, <name>.mtl and every texture of `mesh` (Texture::path is the file stem inside
/// OUTDIR; .png or .jpg is appended). Every file is first written under a temporary name and renamed only once
/// all are complete (the OBJ last), so a failed run leaves no model behind. Positions are written in
/// shortest round-trip form, so they read back bit-identical; texture coordinates likewise, so no UV
/// triangle collapses on the way to the file. Throws InputError naming the path on failure.
void write_obj(const TexturedMesh& mesh, const std::string& outdir, const std::string& name, ImageFormat format);

/// Shortest text that reads back as exactly `value`.
std::string format_double(double value);

}  // namespace tightex
