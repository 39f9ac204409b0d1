// read_model: the reader a model file's extension names.
#include <filesystem>
#include <string>

#include "io/model_files.hpp"
#include "tightex/io.hpp"

namespace tightex {

TexturedMesh read_model(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats) {
  const std::string extension = std::filesystem::path(path).extension().string();
  TexturedMesh mesh = equals_ignoring_case(extension, ".ply")                                                  ? read_ply(path, options, stats)
                      : equals_ignoring_case(extension, ".gltf") || equals_ignoring_case(extension, ".glb") ? read_gltf(path, options, stats)
                                                                                                             : read_obj(path, options, stats);
  const size_t coloured = texture_vertex_colours(mesh, options.max_texture_pixels);
  if (stats != nullptr) stats->vertex_coloured_triangles = coloured;
  return mesh;
}

}  // namespace tightex
