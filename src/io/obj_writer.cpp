#include "io/obj_writer.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>

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

std::pair<uint64_t, uint64_t> key(const Vec2& v) {
  uint64_t a, b;
  std::memcpy(&a, v.data(), 8);
  std::memcpy(&b, v.data() + 1, 8);
  return {a, b};
}

void append(std::string& s, double v) {
  char buf[32];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  s.append(buf, end);
}

/// The MTL statement of each slot that has one (docs: read_obj reads the same).
constexpr std::pair<MaterialSlot, const char*> kMapStatements[] = {
    {MaterialSlot::kSpecular, "map_Ks"}, {MaterialSlot::kEmissive, "map_Ke"},  {MaterialSlot::kRoughness, "map_Pr"},
    {MaterialSlot::kMetallic, "map_Pm"}, {MaterialSlot::kNormal, "norm"},      {MaterialSlot::kBump, "map_Bump"},
    {MaterialSlot::kOpacity, "map_d"},   {MaterialSlot::kShininess, "map_Ns"}, {MaterialSlot::kDisplacement, "disp"}};

/// The MTL statements of a material's other maps (Material::maps) with map_Kd's options; glTF's
/// metallic-roughness image as map_Pr and map_Pm reading its green and blue (-imfchan). A material
/// that did not come from an MTL (no mtl_statements) gets Ks 1 1 1 and Ke 1 1 1 beside map_Ks and
/// map_Ke, which multiply them; one that did keeps its own. glTF's occlusion and the KHR_materials_*
/// slots have no MTL statement and are not written.
std::string map_lines(const Material& m, const std::string& options, const std::vector<std::string>& texture_file) {
  std::string lines;
  for (const auto& [slot, keyword] : kMapStatements) {
    const int tex = m.maps[size_t(slot)];
    if (tex < 0) continue;
    if (slot == MaterialSlot::kSpecular && m.mtl_statements.empty()) lines += "Ks 1 1 1\n";
    if (slot == MaterialSlot::kEmissive && m.mtl_statements.empty()) lines += "Ke 1 1 1\n";
    lines += fmt::format("{} {}{}\n", keyword, options, texture_file[size_t(tex)]);
  }
  const int mr = m.maps[size_t(MaterialSlot::kMetallicRoughness)];
  if (mr >= 0 && m.maps[size_t(MaterialSlot::kRoughness)] < 0 && m.maps[size_t(MaterialSlot::kMetallic)] < 0)
    lines += fmt::format("map_Pr -imfchan g {}{}\nmap_Pm -imfchan b {}{}\n", options, texture_file[size_t(mr)], options,
                         texture_file[size_t(mr)]);
  return lines;
}

/// Whether map_lines writes a statement for `slot` of `m`.
bool map_written(const Material& m, MaterialSlot slot) {
  if (slot == MaterialSlot::kMetallicRoughness)
    return m.maps[size_t(MaterialSlot::kRoughness)] < 0 && m.maps[size_t(MaterialSlot::kMetallic)] < 0;
  return std::any_of(std::begin(kMapStatements), std::end(kMapStatements), [&](const auto& st) { return st.first == slot; });
}

/// The MTL file: one material each with its own statements as read (Material::mtl_statements; the
/// defaults Ka 1 1 1, Ks 0 0 0, d 1, illum 1 for one that came from no MTL), map_Kd naming the texture
/// files as written (`texture_file`).
std::string mtl_text(const TexturedMesh& mesh, const std::vector<std::string>& texture_file) {
  std::string mtl = "# written by tightex\n";
  for (const Material& m : mesh.materials) {
    mtl += fmt::format("\nnewmtl {}\nKd {} {} {}\n", m.name, format_double(m.kd[0]), format_double(m.kd[1]), format_double(m.kd[2]));
    if (m.mtl_statements.empty())
      mtl += m.maps[size_t(MaterialSlot::kSpecular)] >= 0 ? "Ka 1 1 1\nd 1\nillum 1\n" : "Ka 1 1 1\nKs 0 0 0\nd 1\nillum 1\n";
    for (const std::string& statement : m.mtl_statements) mtl += statement + "\n";
    // -s/-o only where the material has them (a copied input material of a kept component).
    std::string options;
    if (m.uv_scale != std::array<double, 2>{1.0, 1.0})
      options += fmt::format("-s {} {} 1 ", format_double(m.uv_scale[0]), format_double(m.uv_scale[1]));
    if (m.uv_offset != std::array<double, 2>{0.0, 0.0})
      options += fmt::format("-o {} {} 0 ", format_double(m.uv_offset[0]), format_double(m.uv_offset[1]));
    if (m.texture >= 0) mtl += fmt::format("map_Kd {}{}\n", options, texture_file[size_t(m.texture)]);
    mtl += map_lines(m, options, texture_file);  // an untextured material's other maps too
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

void append(std::string& s, uint32_t v) {
  char buf[16];
  auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  s.append(buf, end);
}

/// The text of items [0, n) as pieces of about kBlock items each, each piece made by calling
/// `append_item(i, piece)` for its items in order, on every core: the pieces in order are the text one
/// loop over the items would give.
template <typename AppendItem>
void append_pieces(std::vector<std::string>& pieces, size_t n, AppendItem&& append_item) {
  constexpr size_t kBlock = size_t(1) << 14;
  const size_t first = pieces.size(), blocks = (n + kBlock - 1) / kBlock;
  pieces.resize(first + blocks);
  tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
    std::string& piece = pieces[first + b];
    for (size_t i = b * kBlock, end = std::min(n, i + kBlock); i < end; ++i) append_item(i, piece);
  });
}

/// Items numbered by their key the way a map filled in item order numbers them: the items whose key
/// no earlier item has get 0, 1, 2, ... in item order, every other item its key's first item's number.
/// `firsts` gets those first items, in order. A parallel sort by (key, item) instead of n lookups one
/// after the other.
template <typename Key, typename KeyOf>
std::vector<uint32_t> number_by_first_occurrence(size_t n, KeyOf&& key_of, std::vector<uint32_t>& firsts) {
  std::vector<std::pair<Key, uint32_t>> keyed(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) { keyed[i] = {key_of(i), uint32_t(i)}; });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  // Each run of equal keys starts with its first item.
  std::vector<uint32_t> first_of(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    if (i > 0 && keyed[i].first == keyed[i - 1].first) return;
    for (size_t j = i; j < n && keyed[j].first == keyed[i].first; ++j) first_of[keyed[j].second] = keyed[i].second;
  });
  std::vector<uint32_t> number(n);
  firsts.clear();
  for (uint32_t i = 0; i < n; ++i)
    if (first_of[i] == i) number[i] = uint32_t(firsts.size()), firsts.push_back(i);
  tbb::parallel_for(size_t(0), n, [&](size_t i) { number[i] = number[first_of[i]]; });
  return number;
}

/// The "vt" lines, each distinct texture coordinate once (in order of first use); returns each
/// corner's vt index.
std::vector<uint32_t> append_texture_coordinates(const TexturedMesh& mesh, std::vector<std::string>& pieces) {
  std::vector<uint32_t> firsts;
  std::vector<uint32_t> corner_vt = number_by_first_occurrence<std::pair<uint64_t, uint64_t>>(
      mesh.corner_uv.size(), [&](size_t c) { return key(mesh.corner_uv[c]); }, firsts);
  append_pieces(pieces, firsts.size(), [&](size_t i, std::string& text) {
    const Vec2& uv = mesh.corner_uv[firsts[i]];
    text += "vt ";
    append(text, uv.x());
    text += ' ';
    append(text, uv.y());
    text += '\n';
  });
  return corner_vt;
}

/// The bits of a coordinate as its shortest text tells it: every NaN of one sign is the same text.
uint64_t text_bits(double d) {
  if (std::isnan(d)) d = std::signbit(d) ? -std::numeric_limits<double>::quiet_NaN() : std::numeric_limits<double>::quiet_NaN();
  uint64_t b;
  std::memcpy(&b, &d, 8);
  return b;
}

/// The "vn" lines, each distinct normal text once (in order of first use); returns each corner's vn index.
std::vector<uint32_t> append_normals(const TexturedMesh& mesh, std::vector<std::string>& pieces) {
  std::vector<uint32_t> firsts;
  std::vector<uint32_t> corner_vn = number_by_first_occurrence<std::array<uint64_t, 3>>(
      mesh.corner_normal.size(),
      [&](size_t c) {
        const Vec3& n = mesh.corner_normal[c];
        return std::array<uint64_t, 3>{text_bits(n.x()), text_bits(n.y()), text_bits(n.z())};
      },
      firsts);
  append_pieces(pieces, firsts.size(), [&](size_t i, std::string& text) {
    append_vec3(text, "vn ", mesh.corner_normal[firsts[i]]);
    text += '\n';
  });
  return corner_vn;
}

/// The "f" lines, each after a "usemtl" line where the triangle's material differs from the one before.
void append_faces(const TexturedMesh& mesh, const std::vector<uint32_t>& corner_vt, const std::vector<uint32_t>& corner_vn,
                  std::vector<std::string>& pieces) {
  append_pieces(pieces, mesh.num_triangles(), [&](size_t t, std::string& text) {
    const int32_t material = mesh.face_material[t];
    if ((t == 0 || mesh.face_material[t - 1] != material) && material >= 0)
      text += fmt::format("usemtl {}\n", mesh.materials[size_t(material)].name);
    text += 'f';
    for (int k = 0; k < 3; ++k) {
      const size_t c = 3 * t + size_t(k);
      text += ' ';
      append(text, mesh.triangles[t][k] + 1);
      text += '/';
      append(text, corner_vt[c] + 1);
      if (corner_vn.empty()) continue;
      text += '/';
      append(text, corner_vn[c] + 1);
    }
    text += '\n';
  });
}

/// The OBJ file, in pieces written one after the other: positions, texture coordinates, normals (when
/// every corner has one), faces by material. Each part is formatted in blocks on every core.
std::vector<std::string> obj_pieces(const TexturedMesh& mesh, const std::string& name) {
  std::vector<std::string> pieces{
      fmt::format("# written by tightex: {} vertices, {} triangles\nmtllib {}.mtl\n", mesh.num_vertices(), mesh.num_triangles(), name)};
  append_pieces(pieces, mesh.num_vertices(), [&](size_t v, std::string& text) {
    append_vec3(text, "v ", mesh.positions[v]);
    text += '\n';
  });
  const std::vector<uint32_t> corner_vt = append_texture_coordinates(mesh, pieces);
  const bool normals = mesh.corner_normal.size() == mesh.corner_uv.size() && !mesh.corner_normal.empty();
  const std::vector<uint32_t> corner_vn = normals ? append_normals(mesh, pieces) : std::vector<uint32_t>{};
  append_faces(mesh, corner_vt, corner_vn, pieces);
  return pieces;
}

}  // namespace

std::vector<std::string> write_obj(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                   const ImageEncoding& encoding) {
  return write_obj(mesh, outdir, name, encoding, EncodedImages{});
}

std::vector<std::string> write_obj(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                   const ImageEncoding& encoding, const EncodedImages& encoded) {
  std::vector<OutputFile> files = texture_output_files(mesh, encoding, encoded);
  std::vector<std::string> texture_file;
  for (const OutputFile& f : files) texture_file.push_back(f.name);
  files.push_back({name + ".mtl", [&](const fs::path& tmp) { write_whole_file(tmp, mtl_text(mesh, texture_file)); }});
  files.push_back({name + ".obj", [&](const fs::path& tmp) { write_whole_file(tmp, obj_pieces(mesh, name)); }});
  write_files_atomically(outdir, files);
  return unbound_maps(mesh, map_written, "MTL has no statement for it");
}

}  // namespace tightex
