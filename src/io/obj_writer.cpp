#include "io/obj_writer.hpp"

#include <charconv>
#include <cstring>
#include <filesystem>
#include <unordered_map>

#include "core/error.hpp"
#include "io/output_files.hpp"

namespace tightex {

namespace fs = std::filesystem;

std::string format_double(double value) {
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, value);
  return std::string(buf, end);
}

namespace {

struct Vec2Hash {
  size_t operator()(const std::pair<uint64_t, uint64_t>& k) const { return size_t(k.first * 0x9E3779B97F4A7C15ull ^ k.second); }
};
std::pair<uint64_t, uint64_t> key(const Vec2& v) {
  uint64_t a, b;
  std::memcpy(&a, &v.x(), 8);
  std::memcpy(&b, &v.y(), 8);
  return {a, b};
}

void append(std::string& s, double v) {
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  s.append(buf, end);
}

/// The MTL statements of a material's other maps (Material::maps) with map_Kd's options: map_Ks (and
/// Ks 1 1 1, which multiplies it), map_Ke (and Ke 1 1 1), map_Pr, map_Pm, norm, map_Bump; glTF's
/// metallic-roughness image as map_Pr and map_Pm reading its green and blue (-imfchan). glTF's
/// occlusion has no MTL statement and is not written.
std::string map_lines(const Material& m, const std::string& options, const std::vector<std::string>& texture_file) {
  static constexpr std::pair<MapSlot, const char*> kStatements[] = {{MapSlot::kSpecular, "map_Ks"},  {MapSlot::kEmissive, "map_Ke"},
                                                                    {MapSlot::kRoughness, "map_Pr"}, {MapSlot::kMetallic, "map_Pm"},
                                                                    {MapSlot::kNormal, "norm"},      {MapSlot::kBump, "map_Bump"}};
  std::string lines;
  for (const auto& [slot, keyword] : kStatements) {
    const int tex = m.maps[size_t(slot)];
    if (tex < 0) continue;
    if (slot == MapSlot::kSpecular) lines += "Ks 1 1 1\n";
    if (slot == MapSlot::kEmissive) lines += "Ke 1 1 1\n";
    lines += fmt::format("{} {}{}\n", keyword, options, texture_file[size_t(tex)]);
  }
  const int mr = m.maps[size_t(MapSlot::kMetallicRoughness)];
  if (mr >= 0 && m.maps[size_t(MapSlot::kRoughness)] < 0 && m.maps[size_t(MapSlot::kMetallic)] < 0)
    lines += fmt::format("map_Pr -imfchan g {}{}\nmap_Pm -imfchan b {}{}\n", options, texture_file[size_t(mr)], options,
                         texture_file[size_t(mr)]);
  return lines;
}

/// Whether map_lines writes a statement for `slot` of `m`.
bool map_written(const Material& m, MapSlot slot) {
  switch (slot) {
    case MapSlot::kOcclusion:
      return false;
    case MapSlot::kMetallicRoughness:
      return m.maps[size_t(MapSlot::kRoughness)] < 0 && m.maps[size_t(MapSlot::kMetallic)] < 0;
    default:
      return true;
  }
}

/// The MTL file: one material each, map_Kd naming the texture files as written (`texture_file`).
std::string mtl_text(const TexturedMesh& mesh, const std::vector<std::string>& texture_file) {
  std::string mtl = "# written by tightex\n";
  for (const Material& m : mesh.materials) {
    mtl += fmt::format("\nnewmtl {}\nKa 1 1 1\nKd {} {} {}\nKs 0 0 0\nd 1\nillum 1\n", m.name, format_double(m.kd[0]),
                       format_double(m.kd[1]), format_double(m.kd[2]));
    if (m.texture < 0) continue;
    // -s/-o only where the material has them (a copied input material of a kept component).
    std::string options;
    if (m.uv_scale != std::array<double, 2>{1.0, 1.0})
      options += fmt::format("-s {} {} 1 ", format_double(m.uv_scale[0]), format_double(m.uv_scale[1]));
    if (m.uv_offset != std::array<double, 2>{0.0, 0.0})
      options += fmt::format("-o {} {} 0 ", format_double(m.uv_offset[0]), format_double(m.uv_offset[1]));
    mtl += fmt::format("map_Kd {}{}\n", options, texture_file[size_t(m.texture)]);
    mtl += map_lines(m, options, texture_file);
  }
  return mtl;
}

void append_vec3(std::string& out, const char* tag, const Vec3& p) {
  out += tag;
  append(out, p.x());
  out += ' ';
  append(out, p.y());
  out += ' ';
  append(out, p.z());
}

/// The "vt" lines, each distinct texture coordinate once; returns each corner's vt index.
std::vector<uint32_t> append_texture_coordinates(const TexturedMesh& mesh, std::string& obj) {
  std::unordered_map<std::pair<uint64_t, uint64_t>, uint32_t, Vec2Hash> uv_index;
  std::vector<uint32_t> corner_vt(mesh.corner_uv.size());
  for (size_t c = 0; c < mesh.corner_uv.size(); ++c) {
    auto [it, inserted] = uv_index.try_emplace(key(mesh.corner_uv[c]), uint32_t(uv_index.size()));
    if (inserted) {
      obj += "vt ";
      append(obj, mesh.corner_uv[c].x());
      obj += ' ';
      append(obj, mesh.corner_uv[c].y());
      obj += '\n';
    }
    corner_vt[c] = it->second;
  }
  return corner_vt;
}

/// The "vn" lines, each distinct normal once; returns each corner's vn index.
std::vector<uint32_t> append_normals(const TexturedMesh& mesh, std::string& obj) {
  std::unordered_map<std::string, uint32_t> vn_index;
  std::vector<uint32_t> corner_vn(mesh.corner_normal.size());
  for (size_t c = 0; c < mesh.corner_normal.size(); ++c) {
    std::string line;
    append_vec3(line, "vn ", mesh.corner_normal[c]);
    auto [it, inserted] = vn_index.try_emplace(line, uint32_t(vn_index.size()));
    if (inserted) obj += line + '\n';
    corner_vn[c] = it->second;
  }
  return corner_vn;
}

/// The OBJ file: positions, texture coordinates, normals (when every corner has one), faces by material.
std::string obj_text(const TexturedMesh& mesh, const std::string& name) {
  std::string obj;
  obj.reserve(mesh.num_vertices() * 40 + mesh.num_triangles() * 60);
  obj += fmt::format("# written by tightex: {} vertices, {} triangles\nmtllib {}.mtl\n", mesh.num_vertices(), mesh.num_triangles(), name);
  for (const Vec3& p : mesh.positions) {
    append_vec3(obj, "v ", p);
    obj += '\n';
  }
  const std::vector<uint32_t> corner_vt = append_texture_coordinates(mesh, obj);
  const bool normals = mesh.corner_normal.size() == mesh.corner_uv.size() && !mesh.corner_normal.empty();
  const std::vector<uint32_t> corner_vn = normals ? append_normals(mesh, obj) : std::vector<uint32_t>{};
  int32_t current = -2;
  for (size_t t = 0; t < mesh.num_triangles(); ++t) {
    if (mesh.face_material[t] != current) {
      current = mesh.face_material[t];
      if (current >= 0) obj += fmt::format("usemtl {}\n", mesh.materials[size_t(current)].name);
    }
    obj += 'f';
    for (int k = 0; k < 3; ++k) {
      const size_t c = 3 * t + size_t(k);
      if (normals)
        obj += fmt::format(" {}/{}/{}", mesh.triangles[t][k] + 1, corner_vt[c] + 1, corner_vn[c] + 1);
      else
        obj += fmt::format(" {}/{}", mesh.triangles[t][k] + 1, corner_vt[c] + 1);
    }
    obj += '\n';
  }
  return obj;
}

}  // namespace

std::vector<std::string> write_obj(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                   const ImageEncoding& encoding) {
  std::vector<OutputFile> files = texture_output_files(mesh, encoding);
  std::vector<std::string> texture_file;
  for (const OutputFile& f : files) texture_file.push_back(f.name);
  files.push_back({name + ".mtl", [&](const fs::path& tmp) { write_whole_file(tmp, mtl_text(mesh, texture_file)); }});
  files.push_back({name + ".obj", [&](const fs::path& tmp) { write_whole_file(tmp, obj_text(mesh, name)); }});
  write_files_atomically(outdir, files);
  return unbound_maps(mesh, map_written, "MTL has no statement for it");
}

}  // namespace tightex
