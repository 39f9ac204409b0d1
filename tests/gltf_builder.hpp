// Hand-built glTF documents for the tests and the fuzz seeds: a textured grid as a GLB in memory (JSON
// and BIN chunk), with the pieces a test needs to break or change one at a time.
#pragma once
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include <unistd.h>

#include "io/image_io.hpp"
#include "tightex/io.hpp"

namespace tightex::testing {

/// Appends `value`'s bytes (little-endian hosts: the tests' and CI's).
template <typename T>
void append_bytes(std::string& out, T value) {
  char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  out.append(b, sizeof(T));
}

/// A GLB file: header, the JSON chunk (space-padded), the BIN chunk (zero-padded) when `bin` is not empty.
inline std::string make_glb(const nlohmann::json& doc, std::string bin) {
  std::string text = doc.dump();
  while (text.size() % 4 != 0) text.push_back(' ');
  while (bin.size() % 4 != 0) bin.push_back('\0');
  std::string out;
  append_bytes(out, uint32_t(0x46546C67));
  append_bytes(out, uint32_t(2));
  append_bytes(out, uint32_t(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size())));
  append_bytes(out, uint32_t(text.size()));
  append_bytes(out, uint32_t(0x4E4F534A));
  out += text;
  if (!bin.empty()) {
    append_bytes(out, uint32_t(bin.size()));
    append_bytes(out, uint32_t(0x004E4942));
    out += bin;
  }
  return out;
}

/// A small PNG (a colour gradient, `size` x `size`), encoded through save_image.
inline std::string gradient_png(int size = 16) {
  Image img(size, size);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) img.at(x, y) = {uint8_t(x * 255 / size), uint8_t(y * 255 / size), 96, 255};
  // One file per process: test shards run side by side, and save_image truncates the file it writes.
  const std::filesystem::path tmp =
      std::filesystem::temp_directory_path() / ("tightex_gradient_" + std::to_string(size) + "_" + std::to_string(::getpid()) + ".png");
  save_image(tmp.string(), img, ImageFormat::kPng);
  std::string bytes;
  {
    std::ifstream in(tmp, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  std::filesystem::remove(tmp);
  return bytes;
}

/// The grid's document and its buffer: an n x n grid of quads (two triangles each) in z = 0 with
/// positions of no short decimal form, NORMAL, TEXCOORD_0 in [0.1, 0.6], ushort indices, a material with
/// a base colour texture (embedded PNG), a base colour factor, a normal texture and extras; two nodes
/// (a TRS one and a child with a matrix) using the mesh, and a points primitive beside the triangles.
struct GridGltf {
  nlohmann::json doc;
  std::string bin;
  size_t triangles = 0;
};

inline GridGltf grid_gltf(int n = 4) {
  GridGltf g;
  std::string pos, nor, uv, idx, pts;
  const int v = n + 1;
  for (int j = 0; j < v; ++j)
    for (int i = 0; i < v; ++i) {
      append_bytes(pos, float(i / 3.0f + 0.1f)), append_bytes(pos, float(j / 7.0f)), append_bytes(pos, 0.0f);
      append_bytes(nor, 0.0f), append_bytes(nor, 0.0f), append_bytes(nor, 1.0f);
      append_bytes(uv, float(0.1 + 0.5 * i / n)), append_bytes(uv, float(0.1 + 0.5 * j / n));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint16_t a = uint16_t(j * v + i), b = uint16_t(a + 1), c = uint16_t(a + v + 1), d = uint16_t(a + v);
      for (uint16_t x : {a, b, c, a, c, d}) append_bytes(idx, x);
    }
  g.triangles = size_t(2 * n * n);
  for (int k = 0; k < 3; ++k) append_bytes(pts, float(k)), append_bytes(pts, 5.0f), append_bytes(pts, 1.0f);
  const std::string png = gradient_png();
  auto add_view = [&](const std::string& bytes) {
    while (g.bin.size() % 4 != 0) g.bin.push_back('\0');
    nlohmann::json view = {{"buffer", 0}, {"byteOffset", g.bin.size()}, {"byteLength", bytes.size()}};
    g.bin += bytes;
    g.doc["bufferViews"].push_back(view);
    return g.doc["bufferViews"].size() - 1;
  };
  const size_t count = size_t(v * v);
  g.doc["asset"] = {{"version", "2.0"}, {"generator", "tightex tests"}};
  g.doc["accessors"] = nlohmann::json::array();
  auto add_accessor = [&](const std::string& bytes, int type, size_t n_items, const char* kind) {
    g.doc["accessors"].push_back({{"bufferView", add_view(bytes)}, {"componentType", type}, {"count", n_items}, {"type", kind}});
    return g.doc["accessors"].size() - 1;
  };
  const size_t a_pos = add_accessor(pos, 5126, count, "VEC3");
  g.doc["accessors"][a_pos]["min"] = {0.1f, 0.0f, 0.0f};
  g.doc["accessors"][a_pos]["max"] = {float(n / 3.0f + 0.1f), float(n / 7.0f), 0.0f};
  const size_t a_nor = add_accessor(nor, 5126, count, "VEC3");
  const size_t a_uv = add_accessor(uv, 5126, count, "VEC2");
  const size_t a_idx = add_accessor(idx, 5123, size_t(6 * n * n), "SCALAR");
  const size_t a_pts = add_accessor(pts, 5126, 3, "VEC3");
  g.doc["accessors"][a_pts]["min"] = {0.0, 5.0, 1.0};
  g.doc["accessors"][a_pts]["max"] = {2.0, 5.0, 1.0};
  g.doc["images"] = {{{"bufferView", add_view(png)}, {"mimeType", "image/png"}},
                     {{"bufferView", add_view(png)}, {"mimeType", "image/png"}}};
  g.doc["textures"] = {{{"source", 0}}, {{"source", 1}}};
  g.doc["materials"] = {{{"name", "grid material"},
                         {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"baseColorFactor", {0.5, 0.5, 0.5, 1.0}}}},
                         {"normalTexture", {{"index", 1}}},
                         {"doubleSided", true},
                         {"alphaMode", "MASK"},
                         {"alphaCutoff", 0.25},
                         {"extras", {{"scanner", "test"}}}}};
  g.doc["meshes"] = {
      {{"name", "grid"},
       {"extras", {{"id", 7}}},
       {"primitives",
        {{{"attributes", {{"POSITION", a_pos}, {"NORMAL", a_nor}, {"TEXCOORD_0", a_uv}}}, {"indices", a_idx}, {"material", 0}},
         {{"attributes", {{"POSITION", a_pts}}}, {"mode", 0}}}}}};
  g.doc["nodes"] = {{{"name", "root"},
                     {"mesh", 0},
                     {"translation", {0.1, 0.2, 0.30000000000000004}},
                     {"rotation", {0.0, 0.7071067811865476, 0.0, 0.7071067811865476}},
                     {"scale", {2.0, 2.0, 2.0}},
                     {"children", {1}}},
                    {{"name", "child"}, {"mesh", 0}, {"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1.5, 0, -0.25, 1}}}};
  g.doc["scenes"] = {{{"nodes", {0}}, {"name", "scene"}}};
  g.doc["scene"] = 0;
  g.doc["buffers"] = {{{"byteLength", g.bin.size()}}};
  return g;
}

/// Appends `bytes` to the scene's buffer as a new buffer view (4-byte aligned); its index.
inline size_t add_buffer_view(GridGltf& g, const std::string& bytes) {
  while (g.bin.size() % 4 != 0) g.bin.push_back('\0');
  g.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", g.bin.size()}, {"byteLength", bytes.size()}});
  g.bin += bytes;
  g.doc["buffers"][0]["byteLength"] = g.bin.size();
  return g.doc["bufferViews"].size() - 1;
}

/// Appends an accessor of `count` elements over `bytes` (a new buffer view); its index.
inline size_t add_accessor(GridGltf& g, const std::string& bytes, int component_type, size_t count, const char* type) {
  g.doc["accessors"].push_back(
      {{"bufferView", add_buffer_view(g, bytes)}, {"componentType", component_type}, {"count", count}, {"type", type}});
  return g.doc["accessors"].size() - 1;
}

/// A scene as users bring them: the grid's mesh (mesh 0, shown by the grid's two nodes) and a second
/// mesh with the same POSITION accessor but texture coordinates of its own (mesh 1: a second cup beside
/// the first), shown by node 2, moved and mirrored (scale -1 in x). With `untextured_part`, mesh 1 also
/// has a quad whose material has a colour and no texture. Local-space triangles: 2 x grid (+ 2); in
/// world space: 3 x grid (+ 2).
inline GridGltf scene_gltf(bool untextured_part) {
  const int n = 4, v = n + 1;
  GridGltf g = grid_gltf(n);
  std::string uv;
  for (int j = 0; j < v; ++j)
    for (int i = 0; i < v; ++i) append_bytes(uv, float(0.9 - 0.4 * i / n)), append_bytes(uv, float(0.35 + 0.5 * j / n));
  const size_t a_uv = add_accessor(g, uv, 5126, size_t(v * v), "VEC2");
  nlohmann::json copy = g.doc["meshes"][0]["primitives"][0];
  copy["attributes"]["TEXCOORD_0"] = a_uv;
  g.doc["meshes"].push_back({{"name", "copy"}, {"primitives", {copy}}});
  g.doc["nodes"].push_back({{"name", "copy"}, {"mesh", 1}, {"translation", {3.0, 0.0, 0.0}}, {"scale", {-1.0, 1.0, 1.0}}});
  g.doc["scenes"][0]["nodes"] = {0, 2};
  if (untextured_part) {
    std::string pos, idx;
    for (const auto& [x, y] : {std::pair{0.f, 0.f}, {1.f, 0.f}, {1.f, 1.f}, {0.f, 1.f}})
      append_bytes(pos, x), append_bytes(pos, y), append_bytes(pos, 0.5f);
    for (const uint16_t i : {0, 1, 2, 0, 2, 3}) append_bytes(idx, i);
    const size_t a_pos = add_accessor(g, pos, 5126, 4, "VEC3");
    g.doc["accessors"][a_pos]["min"] = {0.0, 0.0, 0.5};
    g.doc["accessors"][a_pos]["max"] = {1.0, 1.0, 0.5};
    const size_t a_idx = add_accessor(g, idx, 5123, 6, "SCALAR");
    g.doc["materials"].push_back({{"name", "plain"}, {"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.4, 0.6, 1.0}}}}});
    g.doc["meshes"][1]["primitives"].push_back({{"attributes", {{"POSITION", a_pos}}}, {"indices", a_idx}, {"material", 1}});
    g.triangles += 2;
  }
  return g;
}

}  // namespace tightex::testing
