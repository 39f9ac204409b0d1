// read_model: the reader a model file's extension names.
#include <filesystem>
#include <string>

#include "io/model_files.hpp"
#include "tightex/io.hpp"

namespace tightex {

TexturedMesh read_model(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats) {
  if (equals_ignoring_case(std::filesystem::path(path).extension().string(), ".ply")) return read_ply(path, options, stats);
  return read_obj(path, options, stats);
}

}  // namespace tightex
