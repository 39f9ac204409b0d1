// read_model: the reader a model file's extension names.
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "io/gltf_document.hpp"
#include "io/image_io.hpp"
#include "io/model_files.hpp"
#include "tightex/io.hpp"

namespace tightex {

namespace {

/// A glTF's textures decoded from its document's bytes, one after another (the reader's order and
/// message: "FILE: images[N]: problem").
void decode_gltf_textures(const TexturedMesh& mesh, std::vector<Texture>& textures, size_t max_pixels) {
  const GltfDocument& doc = *mesh.gltf;
  for (size_t i = 0; i < textures.size() && i < doc.texture_image.size(); ++i) {
    if (!textures[i].image.empty()) continue;
    const std::string_view bytes = doc.images[size_t(doc.texture_image[i])];
    try {
      textures[i].image = decode_image(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(),
                                       fmt::format("images[{}]", doc.texture_image[i]), max_pixels);
    } catch (const InputError& e) {
      fail_input("{}: {}", mesh.source, e.what());
    }
  }
}

}  // namespace

std::vector<Texture> load_texture_pixels(const TexturedMesh& mesh, size_t max_pixels) {
  std::vector<Texture> textures = mesh.textures;
  if (mesh.gltf) {
    decode_gltf_textures(mesh, textures, max_pixels);
    return textures;
  }
  // Errors are kept per texture and the first in the model's order is reported, so the message does
  // not depend on which decode ended first.
  const std::vector<std::string> errors = load_texture_images(textures, max_pixels);
  for (size_t i = 0; i < textures.size(); ++i)
    if (!errors[i].empty())
      fail_input("{} could not be loaded: {}", textures[i].named_at.empty() ? textures[i].path : textures[i].named_at, errors[i]);
  return textures;
}

TexturedMesh read_model(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats) {
  const std::string extension = std::filesystem::path(path).extension().string();
  for (const char* tile : {".b3dm", ".i3dm", ".pnts", ".cmpt"})
    if (equals_ignoring_case(extension, tile))
      fail_input(
          "{}: a 3D Tiles {} payload, not a model: run `python3 -m tightex.tiles` on its tileset.json (it keeps the batch and "
          "feature tables), or give the GLB inside it",
          path, tile + 1);
  TexturedMesh mesh = equals_ignoring_case(extension, ".ply") ? read_ply(path, options, stats)
                      : equals_ignoring_case(extension, ".gltf") || equals_ignoring_case(extension, ".glb")
                          ? read_gltf(path, options, stats)
                          : read_obj(path, options, stats);
  const size_t coloured = texture_vertex_colours(mesh, options.max_texture_pixels);
  if (stats != nullptr) stats->vertex_coloured_triangles = coloured;
  return mesh;
}

}  // namespace tightex
