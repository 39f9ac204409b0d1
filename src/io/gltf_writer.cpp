// glTF 2.0 writer: the input's document with each triangle back in its own primitive (new accessors,
// a copy of its material pointing at the new texture), or a fresh document for an OBJ or PLY input.
// Whatever no longer has a user afterwards (old accessors, buffer views, images, textures) is removed,
// and one buffer holds every byte the document still refers to.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/image.hpp"
#include "core/tangents.hpp"
#include "io/gltf_document.hpp"
#include "io/image_io.hpp"
#include "io/little_endian.hpp"
#include "io/model_files.hpp"
#include "io/output_files.hpp"
#include "tightex/io.hpp"

namespace tightex {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kNewView = "__tightex_new_view";

void pad_to_4(std::string& s, char fill = '\0') {
  while (s.size() % 4 != 0) s.push_back(fill);
}

std::string mime_of(std::string_view bytes) {
  if (bytes.size() >= 4 && bytes.compare(0, 4, "\x89PNG") == 0) return "image/png";
  if (bytes.size() >= 2 && uint8_t(bytes[0]) == 0xFF && uint8_t(bytes[1]) == 0xD8) return "image/jpeg";
  if (bytes.size() >= 12 && bytes.compare(0, 4, "RIFF") == 0 && bytes.compare(8, 4, "WEBP") == 0) return "image/webp";
  if (bytes.size() >= 12 && bytes.compare(1, 3, "KTX") == 0) return "image/ktx2";
  return "application/octet-stream";
}

/// How the written document refers to each output texture's image: a file name (.gltf) or its encoded
/// bytes (.glb).
struct TextureImage {
  std::string uri;
  std::string bytes;
  std::string mime;
  bool webp = false;  // referred to through EXT_texture_webp
};

/// Builds the written document and its one buffer.
class DocumentBuilder {
 public:
  DocumentBuilder(const TexturedMesh& mesh, const std::vector<TextureImage>& images) : mesh_(mesh), images_(images) {}
  /// The JSON document; `bin` receives the buffer's bytes. Returns the removed things in `removed`.
  json build(std::string& bin, std::vector<std::string>& removed);

 private:
  using GroupKey = std::pair<uint32_t, int>;  // (source primitive or output material + 1, output material)
  void start_fresh_document();
  json fresh_pbr(const Material& m);
  std::map<GroupKey, std::vector<uint32_t>> groups() const;
  int new_view(std::string_view bytes, int64_t target);
  int new_accessor(const std::string& bytes, int64_t component_type, size_t count, const char* type, int64_t target,
                   const json& min_max = nullptr);
  json new_primitive(const json& source, int material, const std::vector<uint32_t>& triangles, bool normals,
                     const std::vector<GltfVertexAttribute>* carried = nullptr);
  int carried_accessor(const GltfVertexAttribute& attribute, const std::vector<uint32_t>& vertices);
  int texture_index(int texture);
  int material_for(int source_material, int out_material);
  void bind_map_slots(json& m, const std::string& element, int out_material);
  void replace_triangle_primitives(const std::map<GroupKey, std::vector<uint32_t>>& groups);
  void collect_garbage();
  void rebuild_buffer(std::string& bin);
  void update_extensions_used();

  const TexturedMesh& mesh_;
  const std::vector<TextureImage>& images_;
  const GltfDocument* source_ = nullptr;
  json doc_;
  std::string fresh_bytes_;                         // the new buffer views' bytes, before the rebuild
  std::map<int, int> texture_of_;                   // output texture -> glTF texture
  std::map<std::pair<int, int>, int> material_of_;  // (source material, output material) -> glTF material
  std::set<std::string> removed_;
};

json& array_of(json& doc, const char* name) {
  if (!doc.contains(name) || !doc[name].is_array()) doc[name] = json::array();
  return doc[name];
}

/// The pbrMetallicRoughness of a fresh document's material: its base colour (the texture, times kd
/// where the material came from glTF, whose viewers multiply it; kd alone without a texture) and its
/// metallic and roughness (glTF's factors, or OBJ's Pm and Pr).
json DocumentBuilder::fresh_pbr(const Material& m) {
  const auto& f = m.factor;
  const bool gltf_factors = m.kd_multiplies_texture;
  const double metallic = gltf_factors ? f[size_t(MaterialSlot::kMetallicRoughness)][2] : f[size_t(MaterialSlot::kMetallic)][0];
  const double roughness = gltf_factors ? f[size_t(MaterialSlot::kMetallicRoughness)][1] : f[size_t(MaterialSlot::kRoughness)][0];
  json pbr = {{"metallicFactor", metallic}, {"roughnessFactor", roughness}};
  if (m.texture < 0 || gltf_factors) pbr["baseColorFactor"] = {m.kd[0], m.kd[1], m.kd[2], 1.0};
  if (m.texture >= 0) pbr["baseColorTexture"] = {{"index", texture_index(m.texture)}};
  if (const int t = m.maps[size_t(MaterialSlot::kMetallicRoughness)]; t >= 0)
    pbr["metallicRoughnessTexture"] = {{"index", texture_index(t)}};
  return pbr;
}

void DocumentBuilder::start_fresh_document() {
  const std::string name = fs::path(mesh_.source).stem().string();
  doc_ = {{"asset", {{"version", "2.0"}, {"generator", "tightex"}}},
          {"scene", 0},
          {"scenes", json::array({{{"nodes", json::array({0})}}})},
          {"nodes", json::array({{{"mesh", 0}, {"name", name}}})},
          {"meshes", json::array({{{"name", name}, {"primitives", json::array()}}})}};
  json& materials = array_of(doc_, "materials");
  for (const Material& m : mesh_.materials) {
    json material = {{"name", m.name}, {"pbrMetallicRoughness", fresh_pbr(m)}};
    const auto& f = m.factor;
    if (const int t = m.maps[size_t(MaterialSlot::kOcclusion)]; t >= 0)
      material["occlusionTexture"] = {{"index", texture_index(t)}, {"strength", f[size_t(MaterialSlot::kOcclusion)][0]}};
    const SlotFactor& emissive = f[size_t(MaterialSlot::kEmissive)];
    if (const int t = m.maps[size_t(MaterialSlot::kEmissive)]; t >= 0) material["emissiveTexture"] = {{"index", texture_index(t)}};
    if (emissive[0] != 0 || emissive[1] != 0 || emissive[2] != 0) material["emissiveFactor"] = {emissive[0], emissive[1], emissive[2]};
    if (const int t = m.maps[size_t(MaterialSlot::kNormal)]; t >= 0) material["normalTexture"] = {{"index", texture_index(t)}};
    // A fresh document holds glTF's core slots: OBJ's specular colour, roughness or metallic images
    // alone, height, opacity, shininess and displacement maps have none there.
    for (size_t s = 0; s < kMaterialSlots; ++s) {
      const MaterialSlot slot = MaterialSlot(s);
      const bool core = slot == MaterialSlot::kMetallicRoughness || slot == MaterialSlot::kOcclusion || slot == MaterialSlot::kEmissive ||
                        slot == MaterialSlot::kNormal;
      if (!core && m.maps[s] >= 0) removed_.insert(fmt::format("material {}: its {} map (no glTF slot)", m.name, material_slot_name(slot)));
    }
    materials.push_back(std::move(material));
  }
}

/// The output triangles by where they go: (source primitive, output texture) for a glTF input, (output
/// material, its texture) for a fresh document.
std::map<DocumentBuilder::GroupKey, std::vector<uint32_t>> DocumentBuilder::groups() const {
  std::map<GroupKey, std::vector<uint32_t>> g;
  for (uint32_t t = 0; t < uint32_t(mesh_.num_triangles()); ++t) {
    const int32_t m = mesh_.face_material[t];
    const uint32_t where = source_ != nullptr ? source_->triangle_primitive[mesh_.input_triangle[t]] : uint32_t(m + 1);
    g[{where, m}].push_back(t);
  }
  return g;
}

int DocumentBuilder::new_view(std::string_view bytes, int64_t target) {
  pad_to_4(fresh_bytes_);
  json view = {{"buffer", 0}, {"byteOffset", fresh_bytes_.size()}, {"byteLength", bytes.size()}, {kNewView, true}};
  if (target != 0) view["target"] = target;
  fresh_bytes_ += bytes;
  json& views = array_of(doc_, "bufferViews");
  views.push_back(std::move(view));
  return int(views.size() - 1);
}

int DocumentBuilder::new_accessor(const std::string& bytes, int64_t component_type, size_t count, const char* type, int64_t target,
                                  const json& min_max) {
  json a = {{"bufferView", new_view(bytes, target)}, {"componentType", component_type}, {"count", count}, {"type", type}};
  if (!min_max.is_null()) a["min"] = min_max[0], a["max"] = min_max[1];
  json& accessors = array_of(doc_, "accessors");
  accessors.push_back(std::move(a));
  return int(accessors.size() - 1);
}

/// The glTF texture of output texture `texture`, made on first use with its image.
int DocumentBuilder::texture_index(int texture) {
  const auto found = texture_of_.find(texture);
  if (found != texture_of_.end()) return found->second;
  const TextureImage& ti = images_[size_t(texture)];
  json image = {{"name", mesh_.textures[size_t(texture)].path}};
  if (!ti.uri.empty())
    image["uri"] = ti.uri;
  else
    image["bufferView"] = new_view(ti.bytes, 0), image["mimeType"] = ti.mime;
  json& images = array_of(doc_, "images");
  images.push_back(std::move(image));
  json& textures = array_of(doc_, "textures");
  // A WebP image is a texture's source only through EXT_texture_webp (required: there is no fallback).
  if (ti.webp)
    textures.push_back({{"extensions", {{"EXT_texture_webp", {{"source", images.size() - 1}}}}}});
  else
    textures.push_back({{"source", images.size() - 1}});
  return texture_of_[texture] = int(textures.size() - 1);
}

/// True when `j` holds a texture reference (an object under a key ending in "Texture" with an index).
bool refers_to_texture(const json& j) {
  if (j.is_array()) return std::any_of(j.begin(), j.end(), [](const json& e) { return refers_to_texture(e); });
  if (!j.is_object()) return false;
  for (const auto& [key, value] : j.items()) {
    if (key.size() > 7 && key.compare(key.size() - 7, 7, "Texture") == 0 && value.is_object() && value.contains("index")) return true;
    if (refers_to_texture(value)) return true;
  }
  return false;
}

/// Each texture slot of material copy `m` (kGltfSlots, the KHR_materials_* ones included): pointed at
/// output material `out_material`'s map for it (on TEXCOORD_0, without a transform: the new coordinates
/// are what it samples; scale, strength and extras kept), or removed (noted in removed_) when the output
/// has no such map.
void DocumentBuilder::bind_map_slots(json& m, const std::string& element, int out_material) {
  for (const GltfSlot& s : kGltfSlots) {
    json* holder = gltf_slot_holder(m, s);
    if (holder == nullptr || !holder->contains(s.key)) continue;
    const int texture = out_material >= 0 ? mesh_.materials[size_t(out_material)].maps[size_t(s.slot)] : -1;
    const std::string where = element + (*s.holder != '\0' ? fmt::format(".{}.", s.holder) : std::string(".")) + s.key;
    if (texture < 0) {
      holder->erase(s.key), removed_.insert(where);
      continue;
    }
    json info = {{"index", texture_index(texture)}};
    for (const char* keep : {"scale", "strength", "extras"})
      if ((*holder)[s.key].is_object() && (*holder)[s.key].contains(keep)) info[keep] = (*holder)[s.key][keep];
    (*holder)[s.key] = std::move(info);
  }
}

/// A copy of source material `source_material` (-1: the default) whose base colour is output material
/// `out_material`'s texture on TEXCOORD_0 and whose other slots are its maps; the slots and extension
/// textures that cannot follow the new coordinates are removed.
int DocumentBuilder::material_for(int source_material, int out_material) {
  const int texture = out_material >= 0 ? mesh_.materials[size_t(out_material)].texture : -1;
  if (texture < 0 && source_material >= 0) return source_material;  // untouched: its triangles keep their input UVs
  const auto found = material_of_.find({source_material, out_material});
  if (found != material_of_.end()) return found->second;
  json m = source_material >= 0 ? doc_["materials"][size_t(source_material)] : json::object();
  const std::string element = source_material >= 0 ? fmt::format("materials[{}]", source_material) : std::string("default material");
  if (!m.contains("pbrMetallicRoughness") || !m["pbrMetallicRoughness"].is_object()) m["pbrMetallicRoughness"] = json::object();
  json& pbr = m["pbrMetallicRoughness"];
  bind_map_slots(m, element, out_material);
  if (m.contains("extensions") && m["extensions"].is_object()) {
    std::vector<std::string> drop;
    for (const auto& [key, value] : m["extensions"].items())
      if (!gltf_extension_has_slots(key) && refers_to_texture(value)) drop.push_back(key);
    for (const std::string& key : drop) m["extensions"].erase(key), removed_.insert(element + ".extensions." + key);
    if (m["extensions"].empty()) m.erase("extensions");
  }
  if (texture >= 0) {
    if (!pbr.contains("baseColorTexture") && pbr.contains("baseColorFactor") && pbr["baseColorFactor"].is_array() &&
        pbr["baseColorFactor"].size() == 4)
      pbr["baseColorFactor"] = {1.0, 1.0, 1.0, pbr["baseColorFactor"][3]};  // the flat colour is baked into the texture
    pbr["baseColorTexture"] = {{"index", texture_index(texture)}};
  }
  json& materials = array_of(doc_, "materials");
  materials.push_back(std::move(m));
  return material_of_[{source_material, out_material}] = int(materials.size() - 1);
}

/// An accessor of `attribute`'s elements for the given vertices of the model read (in order), each
/// element copied from the input vertex it is; vertex attributes start every element on 4 bytes, as
/// glTF requires, so an element of 1, 2 or 3 bytes gets a byteStride of 4.
int DocumentBuilder::carried_accessor(const GltfVertexAttribute& attribute, const std::vector<uint32_t>& vertices) {
  const size_t stride = (attribute.element_size + 3) / 4 * 4;
  std::string bytes(stride * vertices.size(), '\0');
  if (attribute.data != nullptr)
    for (size_t i = 0; i < vertices.size(); ++i)
      std::memcpy(bytes.data() + i * stride, attribute.data + size_t(source_->vertex_source[vertices[i]]) * attribute.stride,
                  attribute.element_size);
  const int accessor = new_accessor(bytes, attribute.component_type, vertices.size(), attribute.type.c_str(), 34962);
  json& a = doc_["accessors"][size_t(accessor)];
  if (attribute.normalized) a["normalized"] = true;
  if (stride != attribute.element_size) doc_["bufferViews"][a["bufferView"].get<size_t>()]["byteStride"] = stride;
  return accessor;
}

/// The vertex a corner becomes: its input vertex, texture coordinate and normal, each distinct one once.
struct CornerVertex {
  uint32_t vertex;
  std::array<float, 2> uv;
  std::array<float, 3> normal;
  std::array<float, 4> tangent;
  bool operator<(const CornerVertex& o) const {
    return std::tie(vertex, uv, normal, tangent) < std::tie(o.vertex, o.uv, o.normal, o.tangent);
  }
};

/// One primitive for `triangles` (output triangles): new POSITION, NORMAL (with `normals`), TANGENT (with
/// normals, when the mesh has corner tangents), TEXCOORD_0, the `carried` attributes and indices;
/// `source`'s extras kept.
json DocumentBuilder::new_primitive(const json& source, int material, const std::vector<uint32_t>& triangles, bool normals,
                                    const std::vector<GltfVertexAttribute>* carried) {
  std::map<CornerVertex, uint32_t> index_of;
  std::vector<CornerVertex> vertices;
  std::vector<uint32_t> indices;
  indices.reserve(3 * triangles.size());
  const bool tangents = normals && mesh_.corner_tangent.size() == 3 * mesh_.num_triangles();
  for (const uint32_t t : triangles)
    for (int k = 0; k < 3; ++k) {
      const size_t c = 3 * size_t(t) + size_t(k);
      const Vec2 uv = mesh_.sampled_uv(t, k);  // glTF has no place for a material's -s/-o
      CornerVertex cv{mesh_.triangles[t][size_t(k)], {float(uv.x()), float(1.0 - uv.y())}, {0, 0, 0}, {0, 0, 0, 0}};
      if (normals) {
        const Vec3 n = frame_normal(mesh_, t, k);
        cv.normal = {float(n.x()), float(n.y()), float(n.z())};
      }
      if (tangents) {
        const Vec3 tg = mesh_.corner_tangent[c].head<3>().normalized();
        cv.tangent = {float(tg.x()), float(tg.y()), float(tg.z()), mesh_.corner_tangent[c].w() < 0 ? -1.0f : 1.0f};
      }
      const auto [it, inserted] = index_of.try_emplace(cv, uint32_t(vertices.size()));
      if (inserted) vertices.push_back(cv);
      indices.push_back(it->second);
    }
  std::string pos, nor, tan, uv, idx;
  std::array<float, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  for (const CornerVertex& v : vertices) {
    for (int i = 0; i < 3; ++i) {
      const float x = float(mesh_.positions[v.vertex][i]);
      put(pos, x);
      lo[size_t(i)] = std::min(lo[size_t(i)], x), hi[size_t(i)] = std::max(hi[size_t(i)], x);
      if (normals) put(nor, v.normal[size_t(i)]);
    }
    if (tangents)
      for (const float x : v.tangent) put(tan, x);
    put(uv, v.uv[0]), put(uv, v.uv[1]);
  }
  const bool short_indices = vertices.size() < 65535;  // 65535 is the restart value
  for (const uint32_t i : indices) short_indices ? put(idx, uint16_t(i)) : put(idx, i);
  json p = json::object();
  if (source.is_object() && source.contains("extras")) p["extras"] = source["extras"];
  json& attributes = p["attributes"] = json::object();
  attributes["POSITION"] = new_accessor(pos, 5126, vertices.size(), "VEC3", 34962, json::array({lo, hi}));
  if (normals) attributes["NORMAL"] = new_accessor(nor, 5126, vertices.size(), "VEC3", 34962);
  if (tangents) attributes["TANGENT"] = new_accessor(tan, 5126, vertices.size(), "VEC4", 34962);
  attributes["TEXCOORD_0"] = new_accessor(uv, 5126, vertices.size(), "VEC2", 34962);
  if (carried != nullptr && !carried->empty()) {
    std::vector<uint32_t> input_vertex(vertices.size());
    for (size_t i = 0; i < vertices.size(); ++i) input_vertex[i] = vertices[i].vertex;
    for (const GltfVertexAttribute& attribute : *carried) attributes[attribute.name] = carried_accessor(attribute, input_vertex);
  }
  p["indices"] = new_accessor(idx, short_indices ? 5123 : 5125, indices.size(), "SCALAR", 34963);
  p["material"] = material;
  return p;
}

/// True when every corner of `triangles` has a finite, non-zero normal, or the mesh has tangents (a
/// normal map's frame needs NORMAL beside TANGENT: a mesh without normals gets its flat ones, which
/// shade as glTF's missing normals do).
bool has_normals(const TexturedMesh& mesh, const std::vector<uint32_t>& triangles) {
  if (mesh.corner_tangent.size() == 3 * mesh.num_triangles()) return true;
  if (mesh.corner_normal.size() != 3 * mesh.num_triangles()) return false;
  for (const uint32_t t : triangles)
    for (size_t k = 0; k < 3; ++k) {
      const Vec3& n = mesh.corner_normal[3 * size_t(t) + k];
      if (!n.allFinite() || n.norm() == 0) return false;
    }
  return true;
}

/// Whether `primitive`'s material has a base colour texture (without one, the reader takes its colour
/// from COLOR_0, and the new texture holds those colours).
bool has_base_colour_texture(const json& doc, const json& primitive) {
  if (!primitive.contains("material") || !primitive["material"].is_number_unsigned()) return false;
  const size_t m = primitive["material"].get<size_t>();
  if (!doc.contains("materials") || m >= doc["materials"].size()) return false;
  const json& material = doc["materials"][m];
  return material.contains("pbrMetallicRoughness") && material["pbrMetallicRoughness"].contains("baseColorTexture");
}

bool is_carried(const GltfPrimitive& primitive, const std::string& name) {
  return std::any_of(primitive.carried.begin(), primitive.carried.end(), [&](const GltfVertexAttribute& a) { return a.name == name; });
}

/// Every mesh's triangle primitives replaced by their groups' new primitives, in place and in order;
/// points and lines primitives stay as they were.
void DocumentBuilder::replace_triangle_primitives(const std::map<GroupKey, std::vector<uint32_t>>& groups) {
  std::map<std::pair<size_t, size_t>, std::vector<json>> replacement;  // (mesh, primitive) -> new primitives
  std::set<std::string> dropped_attributes;
  for (const auto& [key, triangles] : groups) {
    if (source_ == nullptr) {
      const int32_t m = int32_t(key.first) - 1;
      json p = new_primitive(json::object(), -1, triangles, has_normals(mesh_, triangles));
      if (m >= 0)
        p["material"] = m;
      else
        p["material"] = material_for(-1, key.second);
      replacement[{0, 0}].push_back(std::move(p));
      continue;
    }
    const GltfPrimitive& sp = source_->primitives[key.first];
    const json& old = doc_["meshes"][sp.mesh]["primitives"][sp.primitive];
    for (const auto& [name, value] : old["attributes"].items())
      if (name != "POSITION" && name != "NORMAL" && name != "TEXCOORD_0" && (name != "TANGENT" || mesh_.corner_tangent.empty()) &&
          !is_carried(sp, name) && !(name == "COLOR_0" && !has_base_colour_texture(source_->json, old)))  // COLOR_0 baked
        dropped_attributes.insert(name);
    if (old.contains("extensions") && old["extensions"].is_object())
      for (const auto& [name, value] : old["extensions"].items())
        removed_.insert(fmt::format("meshes[{}].primitives[{}].extensions.{}", sp.mesh, sp.primitive, name));
    json p = new_primitive(old, material_for(sp.material, key.second), triangles,
                           (sp.normals || !mesh_.corner_tangent.empty()) && has_normals(mesh_, triangles), &sp.carried);
    replacement[{sp.mesh, sp.primitive}].push_back(std::move(p));
  }
  for (const std::string& a : dropped_attributes) removed_.insert("attribute " + a + " of the triangles");
  json& meshes = doc_["meshes"];
  for (size_t m = 0; m < meshes.size(); ++m) {
    json& primitives = meshes[m]["primitives"];
    json rebuilt = json::array();
    for (size_t p = 0; p < primitives.size(); ++p) {
      const auto it = replacement.find({m, p});
      const bool was_read = source_ != nullptr && std::any_of(source_->primitives.begin(), source_->primitives.end(),
                                                              [&](const GltfPrimitive& g) { return g.mesh == m && g.primitive == p; });
      if (it != replacement.end())
        for (json& np : it->second) rebuilt.push_back(std::move(np));
      else if (!was_read)
        rebuilt.push_back(primitives[p]);  // points, lines, a mesh the scene does not reach
    }
    if (source_ == nullptr)
      for (json& np : replacement[{0, 0}]) rebuilt.push_back(std::move(np));
    if (!rebuilt.empty()) primitives = std::move(rebuilt);  // else none of its triangles came out: it stays as it was
  }
}

/// Calls f(index) on every reference to an element of `kind` inside `j` that the collector follows.
template <typename F>
void for_each_texture_reference(json& j, F&& f) {
  if (j.is_array()) {
    for (json& e : j) for_each_texture_reference(e, f);
    return;
  }
  if (!j.is_object()) return;
  for (auto& [key, value] : j.items()) {
    if (key.size() > 7 && key.compare(key.size() - 7, 7, "Texture") == 0 && value.is_object() && value.contains("index") &&
        value["index"].is_number_integer())
      f(value["index"]);
    for_each_texture_reference(value, f);
  }
}

/// Keeps the elements of doc[name] that `used` marks, and returns each old index's new one (-1: gone).
std::vector<int64_t> compact(json& doc, const char* name, const std::vector<bool>& used) {
  std::vector<int64_t> new_index(used.size(), -1);
  if (!doc.contains(name)) return new_index;
  json kept = json::array();
  for (size_t i = 0; i < used.size(); ++i)
    if (used[i]) new_index[i] = int64_t(kept.size()), kept.push_back(std::move(doc[name][i]));
  if (kept.empty())
    doc.erase(name);
  else
    doc[name] = std::move(kept);
  return new_index;
}

/// Marks index `ref` (when it is one) of an array of `size`, or renumbers it with `new_index`.
void mark(const json& ref, std::vector<bool>& used) {
  if (ref.is_number_integer() && ref.get<int64_t>() >= 0 && size_t(ref.get<int64_t>()) < used.size())
    used[size_t(ref.get<int64_t>())] = true;
}
void renumber(json& ref, const std::vector<int64_t>& new_index) {
  if (ref.is_number_integer() && ref.get<int64_t>() >= 0 && size_t(ref.get<int64_t>()) < new_index.size())
    ref = new_index[size_t(ref.get<int64_t>())];
}

/// Calls f(reference) on every accessor reference the document holds that tightex knows of.
template <typename F>
void for_each_accessor_reference(json& doc, F&& f) {
  for (json& mesh : array_of(doc, "meshes"))
    for (json& p : mesh["primitives"]) {
      for (auto& [name, value] : p["attributes"].items()) f(value);
      if (p.contains("indices")) f(p["indices"]);
      if (p.contains("targets"))
        for (json& target : p["targets"])
          for (auto& [name, value] : target.items()) f(value);
    }
  for (json& skin : array_of(doc, "skins"))
    if (skin.contains("inverseBindMatrices")) f(skin["inverseBindMatrices"]);
  for (json& animation : array_of(doc, "animations")) {
    if (!animation.contains("samplers")) continue;
    for (json& sampler : animation["samplers"])
      for (const char* key : {"input", "output"})
        if (sampler.contains(key)) f(sampler[key]);
  }
  for (json& node : array_of(doc, "nodes"))
    if (node.contains("extensions") && node["extensions"].contains("EXT_mesh_gpu_instancing"))
      for (auto& [name, value] : node["extensions"]["EXT_mesh_gpu_instancing"]["attributes"].items()) f(value);
}

/// Removes the materials, textures, images, samplers, accessors and buffer views nothing refers to any
/// more (the replaced primitives' and the dropped texture slots'), renumbering the references.
void DocumentBuilder::collect_garbage() {
  std::vector<bool> used(array_of(doc_, "materials").size(), false);
  for (json& mesh : doc_["meshes"])
    for (json& p : mesh["primitives"])
      if (p.contains("material")) mark(p["material"], used);
  std::vector<int64_t> ni = compact(doc_, "materials", used);
  for (json& mesh : doc_["meshes"])
    for (json& p : mesh["primitives"])
      if (p.contains("material")) renumber(p["material"], ni);
  used.assign(array_of(doc_, "textures").size(), false);
  for_each_texture_reference(array_of(doc_, "materials"), [&](json& r) { mark(r, used); });
  for (size_t i = 0; i < used.size(); ++i)  // a texture's extension (KTX2, WebP, DDS image) goes with it: said
    if (!used[i] && doc_["textures"][i].contains("extensions") && doc_["textures"][i]["extensions"].is_object())
      for (const auto& [name, ext] : doc_["textures"][i]["extensions"].items())
        removed_.insert(fmt::format("textures[{}].extensions.{}", i, name));
  ni = compact(doc_, "textures", used);
  for_each_texture_reference(array_of(doc_, "materials"), [&](json& r) { renumber(r, ni); });
  std::vector<bool> used_images(array_of(doc_, "images").size(), false), used_samplers(array_of(doc_, "samplers").size(), false);
  auto each_image_reference = [&](auto&& f) {
    for (json& t : array_of(doc_, "textures")) {
      if (t.contains("source")) f(t["source"]);
      if (t.contains("extensions"))
        for (auto& [name, ext] : t["extensions"].items())
          if (ext.is_object() && ext.contains("source")) f(ext["source"]);
    }
  };
  each_image_reference([&](json& r) { mark(r, used_images); });
  for (json& t : array_of(doc_, "textures"))
    if (t.contains("sampler")) mark(t["sampler"], used_samplers);
  ni = compact(doc_, "images", used_images);
  each_image_reference([&](json& r) { renumber(r, ni); });
  ni = compact(doc_, "samplers", used_samplers);
  for (json& t : array_of(doc_, "textures"))
    if (t.contains("sampler")) renumber(t["sampler"], ni);
  used.assign(array_of(doc_, "accessors").size(), false);
  for_each_accessor_reference(doc_, [&](json& r) { mark(r, used); });
  ni = compact(doc_, "accessors", used);
  for_each_accessor_reference(doc_, [&](json& r) { renumber(r, ni); });
  for (const char* name : {"materials", "textures", "images", "samplers", "accessors", "skins", "animations"})
    if (doc_.contains(name) && doc_[name].empty()) doc_.erase(name);
}

/// One buffer with every buffer view still used: an old view's bytes copied from its source buffer,
/// a new one's from the new bytes, each at a multiple of 4 (so every accessor stays aligned).
void DocumentBuilder::rebuild_buffer(std::string& bin) {
  std::vector<bool> used(array_of(doc_, "bufferViews").size(), false);
  auto each_view_reference = [&](auto&& f) {
    for (json& a : array_of(doc_, "accessors")) {
      if (a.contains("bufferView")) f(a["bufferView"]);
      if (a.contains("sparse"))
        for (const char* part : {"indices", "values"})
          if (a["sparse"].contains(part)) f(a["sparse"][part]["bufferView"]);
    }
    for (json& image : array_of(doc_, "images"))
      if (image.contains("bufferView")) f(image["bufferView"]);
  };
  each_view_reference([&](json& r) { mark(r, used); });
  const std::vector<int64_t> ni = compact(doc_, "bufferViews", used);
  each_view_reference([&](json& r) { renumber(r, ni); });
  bin.clear();
  for (json& view : array_of(doc_, "bufferViews")) {
    const bool fresh = view.contains(kNewView);
    const std::string_view from = fresh ? std::string_view(fresh_bytes_) : source_->buffers[size_t(view["buffer"].get<int64_t>())];
    const size_t offset = size_t(view.value("byteOffset", uint64_t(0))), length = size_t(view["byteLength"].get<uint64_t>());
    if (offset > from.size() || length > from.size() - offset) fail_internal("buffer view beyond its buffer after the reader's checks");
    pad_to_4(bin);
    view["buffer"] = 0;
    view["byteOffset"] = bin.size();
    view.erase(kNewView);
    bin.append(from, offset, length);
  }
  if (doc_["bufferViews"].empty()) doc_.erase("bufferViews");
  if (bin.empty())
    doc_.erase("buffers");
  else
    doc_["buffers"] = json::array({{{"byteLength", bin.size()}}});
}

/// Collects the names of every extension object in `j`.
void collect_extensions(const json& j, std::set<std::string>& names) {
  if (j.is_array())
    for (const json& e : j) collect_extensions(e, names);
  if (!j.is_object()) return;
  for (const auto& [key, value] : j.items()) {
    if (key == "extensions" && value.is_object())
      for (const auto& [name, ext] : value.items()) names.insert(name);
    collect_extensions(value, names);
  }
}

/// extensionsUsed: the extensions the written document still uses; extensionsRequired: those of them
/// the input required.
void DocumentBuilder::update_extensions_used() {
  std::set<std::string> used;
  collect_extensions(doc_, used);
  // KHR_mesh_quantization has no JSON of its own: kept where the input used it, since the points, lines
  // and carried attributes written back as they were may still be quantized.
  if (doc_.contains("extensionsUsed") && doc_["extensionsUsed"].is_array())
    for (const json& e : doc_["extensionsUsed"])
      if (e == "KHR_mesh_quantization") used.insert("KHR_mesh_quantization");
  std::set<std::string> required;
  if (doc_.contains("extensionsRequired") && doc_["extensionsRequired"].is_array())
    for (const json& e : doc_["extensionsRequired"])
      if (e.is_string() && used.count(e.get<std::string>()) != 0) required.insert(e.get<std::string>());
  // A texture whose only image is WebP (tightex's own, written as WebP) needs the extension.
  for (const json& t : array_of(doc_, "textures"))
    if (!t.contains("source") && t.contains("extensions") && t["extensions"].contains("EXT_texture_webp"))
      required.insert("EXT_texture_webp");
  doc_.erase("extensionsUsed");
  doc_.erase("extensionsRequired");
  if (!used.empty()) doc_["extensionsUsed"] = used;
  if (!required.empty()) doc_["extensionsRequired"] = required;
}

/// Removes every empty array below `j` (a node's `children: []`, a scene's `nodes: []`): glTF allows
/// no empty array, and the input's own are dropped rather than carried into the output. Extras, the
/// application's own data, are left as they are.
void drop_empty_arrays(json& j) {
  if (j.is_array()) {
    for (json& e : j) drop_empty_arrays(e);
    return;
  }
  if (!j.is_object()) return;
  std::vector<std::string> empty;
  for (auto& [key, value] : j.items()) {
    if (key == "extras") continue;
    drop_empty_arrays(value);
    if (value.is_array() && value.empty()) empty.push_back(key);
  }
  for (const std::string& key : empty) j.erase(key);
}

json DocumentBuilder::build(std::string& bin, std::vector<std::string>& removed) {
  source_ = mesh_.gltf && !mesh_.gltf->flattened ? mesh_.gltf.get() : nullptr;  // a flattened scene: a fresh document
  if (source_ != nullptr && mesh_.input_triangle.size() != mesh_.num_triangles())
    fail_internal("write_gltf: a glTF model's output needs input_triangle for each of its {} triangles", mesh_.num_triangles());
  if (source_ != nullptr && source_->vertex_source.size() != mesh_.num_vertices())
    fail_internal("write_gltf: {} vertices, but the glTF read had {}", mesh_.num_vertices(), source_->vertex_source.size());
  if (source_ == nullptr) {
    start_fresh_document();
  } else {
    doc_ = source_->json;
    // Images held in files or data URIs of the input: embedded, since the output has no such files
    // (one buffer view for each file however many images name it).
    std::map<const char*, int> view_of;
    for (size_t i = 0; i < array_of(doc_, "images").size(); ++i) {
      json& image = doc_["images"][i];
      if (!image.contains("uri")) continue;
      const std::string_view bytes = source_->images[i];
      image.erase("uri");
      image["mimeType"] = mime_of(bytes);
      const auto [it, added] = view_of.try_emplace(bytes.data(), 0);
      if (added) it->second = new_view(bytes, 0);
      image["bufferView"] = it->second;
    }
  }
  replace_triangle_primitives(groups());
  collect_garbage();
  rebuild_buffer(bin);
  update_extensions_used();
  // glTF's arrays may not be empty: the walks above create top-level ones the input did not have, and
  // the input may hold its own.
  drop_empty_arrays(doc_);
  removed.assign(removed_.begin(), removed_.end());
  return doc_;
}

/// The .glb file: header, JSON chunk (padded with spaces), BIN chunk (padded with zeros).
std::string glb_bytes(const json& doc, const std::string& bin) {
  std::string text = doc.dump();
  pad_to_4(text, ' ');
  std::string padded_bin = bin;
  pad_to_4(padded_bin);
  std::string out;
  const size_t length = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + padded_bin.size());
  if (length > UINT32_MAX) fail_input("the GLB would be {} bytes, more than a GLB's 4 GiB", length);
  put(out, uint32_t(0x46546C67)), put(out, uint32_t(2)), put(out, uint32_t(length));
  put(out, uint32_t(text.size())), put(out, uint32_t(0x4E4F534A));
  out += text;
  if (!bin.empty()) {
    put(out, uint32_t(padded_bin.size())), put(out, uint32_t(0x004E4942));
    out += padded_bin;
  }
  return out;
}

/// Every texture of `mesh` as `encoding` says (or `encoded`'s bytes), for embedding in a GLB.
std::vector<TextureImage> encoded_textures(const TexturedMesh& mesh, const ImageEncoding& encoding, const EncodedImages& encoded) {
  std::vector<TextureImage> images;
  for (size_t i = 0; i < mesh.textures.size(); ++i) {
    TextureImage ti;
    const ImageEncoding own = encoding.of_texture(i);
    ti.bytes = i < encoded.size() && !encoded[i].empty() ? encoded[i] : encode_image(mesh.textures[i].image, own, mesh.textures[i].path);
    ti.mime = own.format == ImageFormat::kPng ? "image/png" : own.format == ImageFormat::kJpeg ? "image/jpeg" : "image/webp";
    ti.webp = own.format == ImageFormat::kWebp;
    images.push_back(std::move(ti));
  }
  return images;
}

}  // namespace

std::vector<std::string> write_gltf(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                    const ImageEncoding& encoding, GltfContainer container) {
  return write_gltf(mesh, outdir, name, encoding, container, EncodedImages{});
}

std::vector<std::string> write_gltf(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                    const ImageEncoding& encoding, GltfContainer container, const EncodedImages& encoded) {
  std::vector<std::string> removed;
  if (container == GltfContainer::kGlb) {
    check_image_encoding(encoding, (fs::path(outdir) / (name + ".glb")).string());
    write_files_atomically(outdir, {{name + ".glb", [&](const fs::path& tmp) {
                                       const std::vector<TextureImage> images = encoded_textures(mesh, encoding, encoded);
                                       std::string bin;
                                       const json doc = DocumentBuilder(mesh, images).build(bin, removed);
                                       write_whole_file(tmp, glb_bytes(doc, bin));
                                     }}});
    return removed;
  }
  std::vector<OutputFile> files = texture_output_files(mesh, encoding, encoded);
  std::vector<TextureImage> images(files.size());
  for (size_t i = 0; i < files.size(); ++i)
    images[i].uri = files[i].name, images[i].webp = encoding.of_texture(i).format == ImageFormat::kWebp;
  std::string bin;
  json doc = DocumentBuilder(mesh, images).build(bin, removed);
  if (!bin.empty()) {
    doc["buffers"][0]["uri"] = name + ".bin";
    files.push_back({name + ".bin", [&](const fs::path& tmp) { write_whole_file(tmp, bin); }});
  }
  files.push_back({name + ".gltf", [&](const fs::path& tmp) { write_whole_file(tmp, doc.dump(1) + "\n"); }});
  write_files_atomically(outdir, files);
  return removed;
}

}  // namespace tightex
