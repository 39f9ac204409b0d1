#include "pipeline/output_model.hpp"

#include <cctype>
#include <map>
#include <set>

#include "bake/resampling_error.hpp"
#include "core/error.hpp"

namespace tightex {

namespace {

/// The file name of a path without folder and extension ("a/b.c.png" -> "b.c").
std::string file_stem(std::string s) {
  const size_t slash = s.find_last_of('/');
  if (slash != std::string::npos) s = s.substr(slash + 1);
  const size_t dot = s.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? s : s.substr(0, dot);
}

std::string lower(std::string s) {
  for (char& ch : s) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

/// A name that is safe as a file stem and an MTL token: letters, digits, '-', '_' and '.' (not first).
std::string file_name_safe(const std::string& s) {
  std::string r;
  for (char ch : s) r += std::isalnum(static_cast<unsigned char>(ch)) || ch == '-' || ch == '_' || (ch == '.' && !r.empty()) ? ch : '_';
  return r.empty() ? std::string("texture") : r;
}

/// `base`, or base_2, base_3, ... : the first not in `taken` (without case), which it joins.
std::string unique_name(std::set<std::string>& taken, const std::string& base) {
  std::string name = base;
  for (int i = 2; taken.count(lower(name)) != 0; ++i) name = fmt::format("{}_{}", base, i);
  taken.insert(lower(name));
  return name;
}

bool is_kept(const Plan::State& plan, size_t c) { return c < plan.kept.size() && !plan.kept[c].empty(); }

/// The new images some mapped component uses, renumbered densely (a kept component's own image in the
/// per-component layout would stay empty and is not written); -1 for the others.
std::vector<int> renumber_images(const Plan::State& plan, int* new_images) {
  std::vector<int> index(plan.image_size.size(), -1);
  for (size_t c = 0; c < plan.components.size(); ++c)
    if (!is_kept(plan, c)) index[size_t(plan.rects[c].image)] = 0;
  *new_images = 0;
  for (int& i : index)
    if (i == 0) i = (*new_images)++;
  return index;
}

/// Appends triangle t of `input` to `out` with its corners in the order `corner` gives.
void add_input_triangle(const TexturedMesh& input, uint32_t t, const uint8_t* corner, TexturedMesh& out,
                        std::vector<uint8_t>& input_corner) {
  const Tri& it = input.triangles[t];
  input_corner.insert(input_corner.end(), corner, corner + 3);
  out.triangles.push_back(Tri{it[corner[0]], it[corner[1]], it[corner[2]]});
  out.input_triangle.push_back(t);
  if (!input.corner_normal.empty())
    for (int k = 0; k < 3; ++k) out.corner_normal.push_back(input.corner_normal[3 * t + corner[k]]);
}

/// The output material of the mapped triangles of input material `in_mat` (-1: none) on new image
/// `image`, made on first use (OutputModel::mapped_materials): a copy of the input material with the
/// new image as its base colour and no other map yet (bake_material_maps binds them), named as it was
/// (with the image's number where the material spans several).
int32_t mapped_material(const TexturedMesh& input, int32_t in_mat, int image, std::map<std::pair<int32_t, int>, int32_t>& made,
                        std::set<std::string>& names, OutputModel& om) {
  const auto [it, inserted] = made.try_emplace({in_mat, image}, int32_t(om.mesh.materials.size()));
  if (!inserted) return it->second;
  Material m;
  if (in_mat >= 0) m = input.materials[size_t(in_mat)];
  const std::string name = in_mat >= 0 ? m.name : std::string("tightex");
  m.name = unique_name(names, om.new_images == 1 ? name : fmt::format("{}_{}", name, image));
  // An untextured material's colour is baked into the new image: white shows it as it was.
  if (m.texture < 0) m.kd = {1.0, 1.0, 1.0};
  m.texture = image;
  m.maps = unbound_slots();
  m.uv_scale = {1.0, 1.0}, m.uv_offset = {0.0, 0.0};
  om.mesh.materials.push_back(std::move(m));
  om.mapped_materials.push_back({in_mat, image});
  return it->second;
}

/// The mapped components' triangles: new texture coordinates in their rectangles, each input
/// material's copy on its new image (mapped_material).
void add_mapped_triangles(const Plan::State& plan, const TexturedMesh& input, const std::vector<int>& image_index,
                          std::set<std::string>& names, OutputModel& om) {
  std::map<std::pair<int32_t, int>, int32_t> made;
  for (size_t c = 0; c < plan.components.size(); ++c) {
    if (is_kept(plan, c)) continue;
    const Rect& r = plan.rects[c];
    const auto [W, H] = plan.image_size[size_t(r.image)];
    const int image = image_index[size_t(r.image)];
    om.rects.push_back(r);
    om.rects.back().image = image;
    const Surface& disk = plan.disks[c].mesh;
    for (uint32_t f = 0; f < disk.num_faces(); ++f) {
      const uint32_t t = disk.input_face[f];
      if (t == kNone) continue;  // scaffolding
      BakeTriangle bt = bake_triangle(input, disk, f, plan.uv[c], r);
      bt.image = uint32_t(image);
      add_input_triangle(input, t, &disk.input_corner[3 * size_t(f)], om.mesh, om.input_corner);
      for (const Vec2& px : bt.target_px) om.mesh.corner_uv.push_back(Vec2(px.x() / W, 1.0 - px.y() / H));
      om.mesh.face_material.push_back(mapped_material(input, input.face_material[t], image, made, names, om));
      om.bake_triangles.push_back(bt);
    }
  }
}

/// The new textures (black until baked), named after the input file.
void add_new_textures(const Plan::State& plan, const std::vector<int>& image_index, std::set<std::string>& names, OutputModel& om) {
  const std::string stem = file_stem(om.mesh.source);
  for (int i = 0; i < om.new_images; ++i) {
    Texture tex;
    tex.path = om.new_images == 1 ? stem + "_tightex" : fmt::format("{}_tightex_{}", stem, i);
    size_t src = 0;
    while (image_index[src] != i) ++src;
    tex.image = Image(plan.image_size[src].first, plan.image_size[src].second, Rgba8{0, 0, 0, 255});
    names.insert(lower(tex.path));
    om.mesh.textures.push_back(std::move(tex));
  }
}

/// Input material `in_mat` (-1: none) copied for the kept triangles once, with its texture copied under
/// the input file's own stem ("kept_" keeps a copy from ever taking an input texture's own file name);
/// the material keeps its name, renamed only where the name is taken.
int32_t kept_material(const TexturedMesh& input, int32_t in_mat, std::vector<int32_t>& material_of, std::vector<int>& texture_of,
                      std::set<std::string>& names, TexturedMesh& out) {
  int32_t& om = material_of[size_t(in_mat + 1)];
  if (om >= 0) return om;
  Material m;  // no input material: white, as measure() and a renderer take it
  if (in_mat >= 0) m = input.materials[size_t(in_mat)];
  m.texture = -1;
  m.name = unique_name(names, file_name_safe(in_mat >= 0 ? input.materials[size_t(in_mat)].name : "none"));
  // The input's texture copied once under a kept_ name; -1 where it is not loaded.
  auto kept_texture = [&](int in_tex) {
    int& ot = texture_of[size_t(in_tex)];
    if (ot < 0 && !input.textures[size_t(in_tex)].image.empty()) {
      Texture tex;
      tex.path = unique_name(names, "kept_" + file_name_safe(file_stem(input.textures[size_t(in_tex)].path)));
      tex.image = input.textures[size_t(in_tex)].image;
      ot = int(out.textures.size());
      out.textures.push_back(std::move(tex));
    }
    return ot;
  };
  if (in_mat >= 0 && input.materials[size_t(in_mat)].texture >= 0) m.texture = kept_texture(input.materials[size_t(in_mat)].texture);
  for (int& map : m.maps)
    if (map >= 0) map = kept_texture(map);
  om = int32_t(out.materials.size());
  out.materials.push_back(std::move(m));
  return om;
}

/// The kept components' triangles, after the mapped ones: input corners and texture coordinates as
/// they were, each input material they use copied once (first use first, so the order is fixed).
void add_kept_triangles(const Plan::State& plan, const TexturedMesh& input, std::set<std::string>& names, TexturedMesh& out,
                        std::vector<uint8_t>& input_corner) {
  std::vector<int32_t> material_of(input.materials.size() + 1, -1);  // input material + 1 -> output
  std::vector<int> texture_of(input.textures.size(), -1);
  for (size_t c = 0; c < plan.components.size(); ++c) {
    if (!is_kept(plan, c)) continue;
    const Surface& comp = plan.components[c];
    for (uint32_t cf = 0; cf < comp.num_faces(); ++cf) {
      const uint32_t t = comp.input_face[cf];
      const int32_t om = kept_material(input, input.face_material[t], material_of, texture_of, names, out);
      const uint8_t* corner = &comp.input_corner[3 * size_t(cf)];
      add_input_triangle(input, t, corner, out, input_corner);
      for (int k = 0; k < 3; ++k) out.corner_uv.push_back(input.corner_uv[3 * t + corner[k]]);
      out.face_material.push_back(om);
    }
  }
}

/// Which corner of input triangle `r` is at corner `corner` of input triangle `t` (r repeats t: the same
/// three positions).
uint8_t same_corner(const TexturedMesh& input, uint32_t r, uint32_t t, uint8_t corner) {
  const Vec3& p = input.positions[input.triangles[t][corner]];
  for (uint8_t k = 0; k < 3; ++k)
    if (input.positions[input.triangles[r][k]] == p) return k;
  fail_internal("output model: triangle {} repeats triangle {} but lacks its corner {}", r, t, corner);
}

/// The exact repeats of the output's triangles from `first` on (SetAside::repeats), each appended as
/// a copy of the triangle it repeats: its own vertices and normals, the same texture coordinates,
/// material and (for a mapped one) bake triangle.
void add_repeats(const SetAside& set_aside, const TexturedMesh& input, size_t first, OutputModel& om) {
  std::vector<uint32_t> output_of(input.num_triangles(), kNone);
  const size_t end = om.mesh.num_triangles();
  for (size_t o = first; o < end; ++o) output_of[om.mesh.input_triangle[o]] = uint32_t(o);
  const bool mapped = om.bake_triangles.size() == end;
  for (const auto& [r, t] : set_aside.repeats) {
    const uint32_t o = output_of[t];
    if (o == kNone) continue;
    uint8_t corner[3];
    for (size_t k = 0; k < 3; ++k) corner[k] = same_corner(input, r, t, om.input_corner[3 * size_t(o) + k]);
    add_input_triangle(input, r, corner, om.mesh, om.input_corner);
    for (size_t k = 0; k < 3; ++k) om.mesh.corner_uv.push_back(om.mesh.corner_uv[3 * size_t(o) + k]);
    om.mesh.face_material.push_back(om.mesh.face_material[o]);
    if (mapped) om.bake_triangles.push_back(om.bake_triangles[o]);
  }
}

/// The triangles with nothing to bake (SetAside::untextured), last: as they came, each input material
/// copied once (kept_material).
void add_untextured_triangles(const SetAside& set_aside, const TexturedMesh& input, std::set<std::string>& names, OutputModel& om) {
  std::vector<int32_t> material_of(input.materials.size() + 1, -1);
  std::vector<int> texture_of(input.textures.size(), -1);
  static constexpr uint8_t kInOrder[3] = {0, 1, 2};
  for (const uint32_t t : set_aside.untextured) {
    const int32_t m = kept_material(input, input.face_material[t], material_of, texture_of, names, om.mesh);
    add_input_triangle(input, t, kInOrder, om.mesh, om.input_corner);
    for (int k = 0; k < 3; ++k) om.mesh.corner_uv.push_back(input.corner_uv[3 * size_t(t) + size_t(k)]);
    om.mesh.face_material.push_back(m);
  }
}

/// Room for every input triangle in each of the output's per-triangle and per-corner arrays (it holds
/// each at most once): grown one triangle at a time, they would end up to twice their size.
void reserve_triangles(const TexturedMesh& input, OutputModel& om) {
  const size_t n = input.num_triangles();
  om.mesh.triangles.reserve(n);
  om.mesh.input_triangle.reserve(n);
  om.mesh.face_material.reserve(n);
  om.mesh.corner_uv.reserve(3 * n);
  if (!input.corner_normal.empty()) om.mesh.corner_normal.reserve(3 * n);
  om.input_corner.reserve(3 * n);
  om.bake_triangles.reserve(n);
}

}  // namespace

OutputModel build_output_model(const Plan::State& plan, const TexturedMesh& input) {
  OutputModel om;
  om.mesh.source = input.source;
  om.mesh.positions = input.positions;
  om.mesh.gltf = input.gltf;
  om.budget_is_default = plan.budget.is_default;
  om.fixed_map_scales = plan.fixed_map_scales;
  reserve_triangles(input, om);
  const std::vector<int> image_index = renumber_images(plan, &om.new_images);
  std::set<std::string> names;  // file stems and material names taken, compared without case
  add_new_textures(plan, image_index, names, om);
  add_mapped_triangles(plan, input, image_index, names, om);
  add_repeats(plan.set_aside, input, 0, om);
  const size_t kept_from = om.mesh.num_triangles();
  add_kept_triangles(plan, input, names, om.mesh, om.input_corner);
  add_repeats(plan.set_aside, input, kept_from, om);
  add_untextured_triangles(plan.set_aside, input, names, om);
  if (!input.source_mesh.empty())
    for (const uint32_t t : om.mesh.input_triangle) om.mesh.source_mesh.push_back(input.source_mesh[t]);
  return om;
}

}  // namespace tightex
