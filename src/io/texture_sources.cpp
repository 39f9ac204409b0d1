#include "io/texture_sources.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

#include "io/gltf_document.hpp"

namespace tightex {

namespace {

/// The codec of an image from its first bytes (PNG, JPEG, WebP signatures).
std::optional<ImageFormat> format_of(const unsigned char* head, size_t n) {
  if (n >= 8 && std::memcmp(head, "\x89PNG\r\n\x1a\n", 8) == 0) return ImageFormat::kPng;
  if (n >= 3 && head[0] == 0xFF && head[1] == 0xD8 && head[2] == 0xFF) return ImageFormat::kJpeg;
  if (n >= 12 && std::memcmp(head, "RIFF", 4) == 0 && std::memcmp(head + 8, "WEBP", 4) == 0) return ImageFormat::kWebp;
  return std::nullopt;
}

TextureSource file_source(const std::string& path) {
  TextureSource s;
  std::error_code ec;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return s;
  s.bytes = uint64_t(size);
  unsigned char head[16] = {};
  std::ifstream f(path, std::ios::binary);
  f.read(reinterpret_cast<char*>(head), sizeof head);
  s.format = format_of(head, size_t(f.gcount()));
  return s;
}

}  // namespace

std::vector<TextureSource> texture_sources(const TexturedMesh& mesh) {
  std::vector<TextureSource> sources(mesh.textures.size());
  for (size_t i = 0; i < mesh.textures.size(); ++i) {
    const Texture& t = mesh.textures[i];
    if (t.from_vertex_colours) continue;
    if (mesh.gltf && i < mesh.gltf->texture_image.size()) {
      const std::string_view bytes = mesh.gltf->images[size_t(mesh.gltf->texture_image[i])];
      sources[i] = {uint64_t(bytes.size()), format_of(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size())};
    } else {
      sources[i] = file_source(t.path);
    }
  }
  return sources;
}

namespace {

/// The codec shared by the images `bound` gives for each material (-1: none), or nullopt.
std::optional<ImageFormat> shared_format(const TexturedMesh& mesh, const std::vector<TextureSource>& sources,
                                         const std::function<int(const Material&)>& bound) {
  std::optional<ImageFormat> shared;
  bool any = false;
  for (const Material& m : mesh.materials) {
    const int t = bound(m);
    if (t < 0) continue;
    const std::optional<ImageFormat> f = sources[size_t(t)].format;
    if (!f || (any && f != shared)) return std::nullopt;
    shared = f, any = true;
  }
  return shared;
}

}  // namespace

std::optional<ImageFormat> base_colour_format(const TexturedMesh& mesh, const std::vector<TextureSource>& sources) {
  return shared_format(mesh, sources, [](const Material& m) { return m.texture; });
}

std::optional<ImageFormat> material_map_format(const TexturedMesh& mesh, const std::vector<TextureSource>& sources, MaterialSlot slot) {
  return shared_format(mesh, sources, [slot](const Material& m) { return m.maps[size_t(slot)]; });
}

}  // namespace tightex
