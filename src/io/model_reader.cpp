// read_model: the reader a model file's extension names.
#include <filesystem>
#include <string>

#include "io/model_files.hpp"
#include "tightex/io.hpp"

namespace tightex {

TexturedMesh read_model(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats) {
  const std::string extension = std::filesystem::path(path).extension().string();
  if (equals_ignoring_case(extension, ".ply")) return read_ply(path, options, stats);
  if (equals_ignoring_case(extension, ".gltf") || equals_ignoring_case(extension, ".glb")) return read_gltf(path, options, stats);
  return read_obj(path, options, stats);
}

}  // namespace tightex
