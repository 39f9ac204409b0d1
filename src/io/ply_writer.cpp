// The PLY writer: binary little endian, per-face texcoord and texnumber, textures named by
// `comment TextureFile` (the layout OpenMVS and MeshLab write and read).
#include <bit>
#include <climits>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/little_endian.hpp"
#include "io/output_files.hpp"
#include "tightex/io.hpp"

namespace tightex {

namespace fs = std::filesystem;

namespace {

/// True when every coordinate reads back bit-identical from a float.
bool positions_fit_float(const TexturedMesh& mesh) {
  for (const Vec3& p : mesh.positions)
    for (int i = 0; i < 3; ++i)
      if (double(float(p[i])) != p[i]) return false;
  return true;
}

/// Per texture, its page: the textures some material binds as its base colour numbered in order
/// (texnumber and `comment TextureFile` name only these; a PLY reader takes every TextureFile for a
/// page), -1 for the others.
std::vector<int32_t> texture_pages(const TexturedMesh& mesh) {
  std::vector<int32_t> page(mesh.textures.size(), -1);
  for (const Material& m : mesh.materials)
    if (m.texture >= 0) page[size_t(m.texture)] = 0;
  int32_t next = 0;
  for (int32_t& p : page)
    if (p == 0) p = next++;
  return page;
}

/// The page a face's texnumber names: its material's base colour's, or -1.
int32_t face_page(const TexturedMesh& mesh, const std::vector<int32_t>& page, size_t t) {
  const int32_t m = mesh.face_material[t];
  return m < 0 || mesh.materials[size_t(m)].texture < 0 ? -1 : page[size_t(mesh.materials[size_t(m)].texture)];
}

std::string ply_header(const TexturedMesh& mesh, const std::vector<std::string>& texture_file, bool float_positions) {
  std::string h = "ply\nformat binary_little_endian 1.0\ncomment written by tightex\n";
  for (const std::string& file : texture_file) h += fmt::format("comment TextureFile {}\n", file);
  const char* type = float_positions ? "float" : "double";
  h += fmt::format("element vertex {}\nproperty {} x\nproperty {} y\nproperty {} z\n", mesh.num_vertices(), type, type, type);
  h += fmt::format("element face {}\n", mesh.num_triangles());
  h += "property list uchar int vertex_indices\nproperty list uchar float texcoord\nproperty int texnumber\nend_header\n";
  return h;
}

/// The whole PLY file: header, vertices, faces. `texture_file`: the file of each page (texture_pages).
std::string ply_bytes(const TexturedMesh& mesh, const std::vector<std::string>& texture_file, const std::vector<int32_t>& page) {
  const bool float_positions = positions_fit_float(mesh);
  std::string out = ply_header(mesh, texture_file, float_positions);
  out.reserve(out.size() + mesh.num_vertices() * (float_positions ? 12 : 24) + mesh.num_triangles() * 42);
  for (const Vec3& p : mesh.positions)
    for (int i = 0; i < 3; ++i) float_positions ? put(out, float(p[i])) : put(out, p[i]);
  for (size_t t = 0; t < mesh.num_triangles(); ++t) {
    put(out, uint8_t(3));
    for (const uint32_t v : mesh.triangles[t]) put(out, int32_t(v));
    put(out, uint8_t(6));
    for (int k = 0; k < 3; ++k) {
      const Vec2 uv = mesh.sampled_uv(t, k);
      put(out, float(uv.x()));
      put(out, float(uv.y()));
    }
    put(out, face_page(mesh, page, t));
  }
  return out;
}

}  // namespace

std::vector<std::string> write_ply(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                   const ImageEncoding& encoding) {
  return write_ply(mesh, outdir, name, encoding, EncodedImages{});
}

std::vector<std::string> write_ply(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                   const ImageEncoding& encoding, const EncodedImages& encoded) {
  const std::string ply_name = name + ".ply";
  if (mesh.num_vertices() > size_t(INT32_MAX))
    fail_input("{}: {} vertices are more than a PLY's int vertex indices can name", (fs::path(outdir) / ply_name).string(),
               mesh.num_vertices());
  std::vector<OutputFile> files = texture_output_files(mesh, encoding, encoded);
  const std::vector<int32_t> page = texture_pages(mesh);
  std::vector<std::string> texture_file;
  for (size_t i = 0; i < files.size(); ++i)
    if (page[i] >= 0) texture_file.push_back(files[i].name);
  files.push_back({ply_name, [&](const fs::path& tmp) { write_whole_file(tmp, ply_bytes(mesh, texture_file, page)); }});
  write_files_atomically(outdir, files);
  return unbound_maps(
      mesh, [](const Material&, MaterialSlot) { return false; }, "PLY has no material maps; its image is written beside the model");
}

}  // namespace tightex
