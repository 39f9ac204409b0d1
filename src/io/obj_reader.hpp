// Reading Wavefront OBJ + MTL, with every texture image the materials name.
//
// tightex parses OBJ itself rather than through tinyobjloader: a pipeline that runs unattended over
// thousands of scans needs every malformed line refused with its file and line number, which
// tinyobjloader's loader does not give for bad indices or numbers.
#pragma once
#include <string>
#include <vector>

#include "core/mesh.hpp"

namespace tightex {

struct ObjReadOptions {
  bool load_textures = true;              // false: materials keep their texture path, no pixels
  size_t max_texture_pixels = size_t(1) << 30;
};

/// What the reader did beyond plain reading, for the report.
struct ObjReadStats {
  size_t polygons_triangulated = 0;  // faces with more than 3 corners, fan-triangulated
  size_t lines = 0;
  /// Files the MTL names that were found only by ignoring case or by a tail of the path as written
  /// ("WRITTEN -> USED"), e.g. a Windows exporter's absolute path.
  std::vector<std::string> paths_found;
};

/// Reads an OBJ file and its MTL libraries and textures.
/// Requires: a readable OBJ file with at least one triangle and texture coordinates on every face.
/// Guarantees: positions finite; triangle indices in range; corner_uv finite and 3 per triangle;
/// face_material in range or -1; every material with map_Kd has a loaded texture.
/// Throws InputError with "FILE:LINE: problem" for any malformed or unsupported content.
TexturedMesh read_obj(const std::string& path, const ObjReadOptions& options = {}, ObjReadStats* stats = nullptr);

}  // namespace tightex
