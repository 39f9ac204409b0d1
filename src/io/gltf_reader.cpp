// glTF 2.0 reader (.gltf with external or data-URI buffers and images, .glb). The JSON is parsed with
// nlohmann::json and every index, offset, count and stride is checked against the document and the
// buffers' real sizes before a byte is read, so a lying file ends in one InputError line naming the
// file and the element ("FILE: accessors[3]: ...").
#include <tbb/parallel_for.h>
#include <Eigen/Geometry>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/eigen_vector.hpp"
#include "core/error.hpp"
#include "core/image.hpp"
#include "io/gltf_document.hpp"
#include "io/image_io.hpp"
#include "io/model_files.hpp"
#include "tightex/io.hpp"

namespace tightex {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int64_t kFloat = 5126, kUnsignedByte = 5121, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr int64_t kRepeat = 10497;
// A texture coordinate this far outside [0,1] reads the same under every wrap mode to well within a
// texel of any texture (exporters write -1e-7 for 0).
constexpr double kWrapSlack = 1e-4;
constexpr uint32_t kGlbMagic = 0x46546C67, kChunkJson = 0x4E4F534A, kChunkBin = 0x004E4942;
// Corners the primitives may read per byte of the model file and the files it names (a triangle strip
// with byte indices reaches 3), and beyond that budget a fixed allowance for tiny files.
constexpr uint64_t kCornersPerInputByte = 4, kCornerSlack = uint64_t(1) << 20;

uint32_t le32(const char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  if constexpr (std::endian::native == std::endian::big) v = __builtin_bswap32(v);
  return v;
}

/// A value of T stored little-endian at p.
template <typename T>
T load_le(const unsigned char* p) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if constexpr (std::endian::native == std::endian::big)
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  T v;
  std::memcpy(&v, bytes, sizeof(T));
  return v;
}

/// Decodes standard base64 (padding optional). False on any other character.
bool decode_base64(std::string_view in, std::string& out) {
  static const auto table = [] {
    std::array<int8_t, 256> t{};
    t.fill(-1);
    const char* chars = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    for (int i = 0; i < 64; ++i) t[size_t(uint8_t(chars[i]))] = int8_t(i);
    return t;
  }();
  while (!in.empty() && in.back() == '=') in.remove_suffix(1);
  out.clear();
  out.reserve(in.size() / 4 * 3 + 3);
  uint32_t acc = 0;
  int bits = 0;
  for (const char ch : in) {
    const int8_t v = table[size_t(uint8_t(ch))];
    if (v < 0) return false;
    acc = (acc << 6) | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(char((acc >> bits) & 0xFF));
    }
  }
  return true;
}

/// A URI's %XX escapes decoded (a file name with spaces is written "a%20b.png").
std::string percent_decoded(std::string_view uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(uint8_t(uri[i + 1])) && std::isxdigit(uint8_t(uri[i + 2]))) {
      out.push_back(char(std::stoi(std::string(uri.substr(i + 1, 2)), nullptr, 16)));
      i += 2;
    } else {
      out.push_back(uri[i]);
    }
  }
  return out;
}

/// The bytes of one accessor, checked: `count` elements of `components` values each, `stride` apart.
struct AccessorView {
  const unsigned char* data = nullptr;
  size_t count = 0, stride = 0, components = 0;
  int64_t component_type = 0;
  bool normalized = false;

  /// Component k of element i as a double (normalized integers mapped to [0,1] or [-1,1]).
  double get(size_t i, size_t k) const {
    const unsigned char* p = data + i * stride + k * gltf_component_size(component_type);
    switch (component_type) {
      case kFloat:
        return double(load_le<float>(p));
      case kUnsignedByte:
        return normalized ? p[0] / 255.0 : double(p[0]);
      case kUnsignedShort:
        return normalized ? load_le<uint16_t>(p) / 65535.0 : double(load_le<uint16_t>(p));
      case kUnsignedInt:
        return double(load_le<uint32_t>(p));
      case 5120:
        return normalized ? std::max(int8_t(p[0]) / 127.0, -1.0) : double(int8_t(p[0]));
      default:
        return normalized ? std::max(load_le<int16_t>(p) / 32767.0, -1.0) : double(load_le<int16_t>(p));
    }
  }
};

/// Whether tightex can read a model that requires extension `e`: the texture coordinates' transform,
/// WebP and KTX2 images (a KTX2 texture needs a fallback source, texture_for), quantized attributes,
/// lights (nodes' data, written back as they are) and material extensions (written back where they
/// name no texture; one that does is removed, and said).
bool required_extension_understood(const json& e) {
  if (!e.is_string()) return false;
  const std::string name = e.get<std::string>();
  for (const char* known :
       {"KHR_texture_transform", "EXT_texture_webp", "KHR_texture_basisu", "KHR_mesh_quantization", "KHR_lights_punctual"})
    if (name == known) return true;
  return name.rfind("KHR_materials_", 0) == 0;
}

/// A node that shows a mesh: the mesh, and the node's transform to world space (its ancestors' composed).
struct MeshInstance {
  size_t mesh = 0;
  Eigen::Matrix4d world = Eigen::Matrix4d::Identity();
};

/// The most triangles a scene flattened to world space may hold (its instances multiply its meshes'):
/// beyond that a glTF output, which keeps the instancing, is the way.
constexpr uint64_t kMaxFlattenedTriangles = uint64_t(1) << 27;

/// What the reader collects while it walks the scene.
/// A per-corner array of the mesh (normals, tangents, colours), `corners` long once a primitive that
/// has the attribute (`present`) is read: the corners before it get `fill`, as do the corners of a
/// later primitive without it. Stays empty while no primitive has it. Returns `present` (the primitive
/// writes its own values).
template <typename T>
bool grow_corner_attribute(std::vector<T>& values, bool present, size_t corners, const T& fill) {
  if (present || !values.empty()) values.resize(corners, fill);
  return present;
}

struct ReadState {
  TexturedMesh mesh;
  std::map<int, int32_t> material_of;  // glTF material (-1: default) -> TexturedMesh material
  std::map<int, int> texture_of;       // glTF image -> TexturedMesh texture
  bool any_normals = false, any_colors = false, any_tangents = false;
  std::vector<uint8_t> corner_has_normal;  // per corner, while normals are partial
  std::set<int64_t> fallbacks_noted;       // textures read from their fallback source, each said once
};

class GltfReader {
 public:
  GltfReader(const std::string& path, const ModelReadOptions& options)
      : path_(path), options_(options), folder_(fs::path(path).parent_path()) {}
  TexturedMesh read(ModelReadStats* stats);

 private:
  template <typename... Args>
  [[noreturn]] void fail(const std::string& element, fmt::format_string<Args...> f, Args&&... args) const {
    fail_input("{}: {}: {}", path_, element, fmt::format(f, std::forward<Args>(args)...));
  }
  const json& array(const char* name) const;
  const json& item(const char* array_name, int64_t index, const std::string& referrer) const;
  int64_t index_in(const json& object, const char* key, const char* array_name, const std::string& element) const;
  uint64_t unsigned_of(const json& object, const char* key, uint64_t fallback, const std::string& element) const;
  std::string_view bytes_of_uri(const std::string& uri, const std::string& element);
  void load_buffers(std::string_view bin);
  void load_images();
  void check_buffer_views() const;
  void check_document_shape() const;
  void check_index_member(const json& j, const char* key, const std::string& element) const;
  template <typename F>
  void each_object(const json& j, const char* key, const std::string& element, F&& f) const;
  AccessorView accessor(int64_t index, const std::string& element) const;
  AccessorView attribute(const json& primitive, const std::string& name, const std::string& element, bool required) const;
  std::vector<MeshInstance> scene_instances() const;
  Eigen::Matrix4d node_matrix(const json& node, const std::string& element) const;
  std::vector<double> numbers_of(const json& node, const char* key, size_t count, const std::string& element) const;
  TexturedMesh flattened(const TexturedMesh& local, const std::vector<MeshInstance>& instances) const;
  void read_primitive(size_t m, size_t p, ReadState& state);
  void check_finite_entries(const std::vector<uint32_t>& used, const AccessorView& a, const char* name, const std::string& element) const;
  std::vector<Tri> primitive_triangles(const json& primitive, size_t vertices, int64_t mode, const std::string& element) const;
  void check_supported(const json& primitive, const std::string& element) const;
  int32_t material_for(int material, ReadState& state);
  std::vector<GltfVertexAttribute> carried_attributes(const json& primitive, const std::string& uv_set, bool colours_baked, size_t n,
                                                      const std::string& element) const;
  std::string read_corner_uvs(const json& primitive, int material, const std::vector<Tri>& tris, size_t n, const std::string& element,
                              ReadState& state);
  void finish_normals(ReadState& state) const;
  std::array<int64_t, 2> sampler_wrap(const json& info) const;
  void load_textures(TexturedMesh& mesh);
  int texture_for(const json& info, const std::string& t_element, ReadState& state);
  void read_map_slots(const json& g, const json* base, const std::string& element, ReadState& state, Material& m);

  std::string path_;
  ModelReadOptions options_;
  fs::path folder_;
  std::shared_ptr<GltfDocument> doc_ = std::make_shared<GltfDocument>();
  std::vector<std::string> not_read_;
  std::vector<std::string> warnings_;
  std::map<std::string, std::string_view> files_;  // each file a URI names, read once
  uint64_t input_bytes_ = 0;                       // the model file and every file it names: the corner budget
  uint64_t corners_read_ = 0;
  bool quantized_ = false;  // extensionsUsed names KHR_mesh_quantization: integer positions, normals, UVs
};

/// Whether an accessor of `type` may hold a vertex attribute under KHR_mesh_quantization's rules (or
/// glTF's own without it): POSITION float, or any 8/16-bit integer type; NORMAL and TANGENT float, or
/// normalized signed 8/16-bit; TEXCOORD float, normalized unsigned 8/16-bit, and with quantization any 8/16-bit
/// integer type, normalized or not.
bool attribute_type_allowed(const std::string& attribute, int64_t type, bool normalized, bool quantized) {
  const bool small_integer = type >= 5120 && type <= 5123;
  if (type == kFloat) return true;
  if (attribute == "POSITION") return quantized && small_integer;
  if (attribute == "NORMAL" || attribute == "TANGENT") return quantized && normalized && (type == 5120 || type == 5122);
  // TEXCOORD_n
  return (normalized && (type == kUnsignedByte || type == kUnsignedShort)) || (quantized && small_integer);
}

const json& GltfReader::array(const char* name) const {
  static const json empty = json::array();
  const auto it = doc_->json.find(name);
  if (it == doc_->json.end()) return empty;
  if (!it->is_array()) fail(name, "is not an array");
  return *it;
}

const json& GltfReader::item(const char* array_name, int64_t index, const std::string& referrer) const {
  const json& a = array(array_name);
  if (index < 0 || size_t(index) >= a.size())
    fail(referrer, "refers to {}[{}], but the file has {} {}", array_name, index, a.size(), array_name);
  const json& v = a[size_t(index)];
  if (!v.is_object()) fail(fmt::format("{}[{}]", array_name, index), "is not an object");
  return v;
}

int64_t GltfReader::index_in(const json& object, const char* key, const char* array_name, const std::string& element) const {
  const auto it = object.find(key);
  if (it == object.end()) return -1;
  if (!it->is_number_integer()) fail(element, "{} is not an integer index", key);
  const int64_t index = it->get<int64_t>();
  item(array_name, index, fmt::format("{}.{}", element, key));
  return index;
}

uint64_t GltfReader::unsigned_of(const json& object, const char* key, uint64_t fallback, const std::string& element) const {
  const auto it = object.find(key);
  if (it == object.end()) return fallback;
  if (!it->is_number_integer() || it->get<int64_t>() < 0) fail(element, "{} is not a non-negative integer", key);
  return it->get<uint64_t>();
}

/// The bytes a URI names: a base64 data URI, or a file relative to the model's folder (read once
/// however many URIs name it, so a document naming one file a thousand times holds it once).
std::string_view GltfReader::bytes_of_uri(const std::string& uri, const std::string& element) {
  if (uri.rfind("data:", 0) == 0) {
    const size_t comma = uri.find(',');
    if (comma == std::string::npos || uri.substr(0, comma).find(";base64") == std::string::npos)
      fail(element, "data URI is not base64 ('{}')", excerpt(uri));
    std::string bytes;
    if (!decode_base64(std::string_view(uri).substr(comma + 1), bytes)) fail(element, "data URI does not decode (not base64)");
    return doc_->storage.emplace_back(std::move(bytes));
  }
  const std::string written = with_forward_slashes(percent_decoded(uri));
  const NamedFile named = find_named_file(folder_, written, options_.allow_outside_files);
  if (!named.refused.empty()) fail(element, "uri '{}' {}", excerpt(written), named.refused);
  const std::optional<fs::path>& found = named.path;
  if (!found) fail(element, "file '{}' not found", excerpt(written));
  std::error_code ec;
  const std::string key = fs::weakly_canonical(*found, ec).string();
  const auto cached = files_.find(key);
  if (cached != files_.end()) return cached->second;
  std::string bytes, reason;
  if (!read_whole_file(*found, bytes, reason, true)) fail(element, "file '{}' {}", excerpt(written), reason);
  input_bytes_ += bytes.size();
  return files_[key] = doc_->storage.emplace_back(std::move(bytes));
}

void GltfReader::load_buffers(std::string_view bin) {
  const json& buffers = array("buffers");
  for (size_t i = 0; i < buffers.size(); ++i) {
    const std::string element = fmt::format("buffers[{}]", i);
    const json& b = item("buffers", int64_t(i), element);
    const uint64_t length = unsigned_of(b, "byteLength", 0, element);
    if (length == 0) fail(element, "byteLength missing or 0");
    std::string_view bytes;
    const auto uri = b.find("uri");
    if (uri == b.end()) {
      if (i != 0 || bin.data() == nullptr) fail(element, "has no uri and the file has no GLB BIN chunk for it");
      bytes = bin;
    } else {
      if (!uri->is_string()) fail(element, "uri is not a string");
      bytes = bytes_of_uri(uri->get<std::string>(), element);
    }
    if (bytes.size() < length) fail(element, "byteLength is {} but the data holds {} bytes", length, bytes.size());
    doc_->buffers.push_back(bytes.substr(0, size_t(length)));
  }
}

/// Fails unless `j` is an object whose `key`, when present, is an integer (an index).
void GltfReader::check_index_member(const json& j, const char* key, const std::string& element) const {
  if (j.contains(key) && !j[key].is_number_integer()) fail(element, "{} is not an integer index", key);
}

/// Fails unless `j[key]`, when present, is an array of objects; calls f(object, element) on each.
template <typename F>
void GltfReader::each_object(const json& j, const char* key, const std::string& element, F&& f) const {
  if (!j.contains(key)) return;
  const json& a = j[key];
  const std::string name = element.empty() ? std::string(key) : element + "." + key;
  if (!a.is_array()) fail(name, "is not an array");
  for (size_t i = 0; i < a.size(); ++i) {
    const std::string e = fmt::format("{}[{}]", name, i);
    if (!a[i].is_object()) fail(e, "is not an object");
    f(a[i], e);
  }
}

/// The shape of every part of the document the writer walks (also those the reader does not read:
/// unreached meshes, skins, animations), so that writing back what was read cannot meet a surprise.
void GltfReader::check_document_shape() const {
  auto integer_values = [&](const json& o, const std::string& element) {
    if (!o.is_object()) fail(element, "is not an object");
    for (const auto& [name, value] : o.items())
      if (!value.is_number_integer()) fail(element, "{} is not an integer index", name);
  };
  const json& doc = doc_->json;
  each_object(doc, "meshes", "", [&](const json& mesh, const std::string& e) {
    if (!mesh.contains("primitives")) fail(e, "primitives missing");
    each_object(mesh, "primitives", e, [&](const json& p, const std::string& pe) {
      integer_values(p.contains("attributes") ? p["attributes"] : json(), pe + ".attributes");
      check_index_member(p, "indices", pe), check_index_member(p, "material", pe);
      each_object(p, "targets", pe, [&](const json& t, const std::string& te) { integer_values(t, te); });
    });
  });
  each_object(doc, "skins", "", [&](const json& skin, const std::string& e) { check_index_member(skin, "inverseBindMatrices", e); });
  each_object(doc, "animations", "", [&](const json& a, const std::string& e) {
    each_object(a, "samplers", e, [&](const json& sampler, const std::string& se) {
      check_index_member(sampler, "input", se), check_index_member(sampler, "output", se);
    });
  });
  each_object(doc, "nodes", "", [&](const json& node, const std::string& e) {
    if (node.contains("extensions") && node["extensions"].is_object() && node["extensions"].contains("EXT_mesh_gpu_instancing")) {
      const json& ext = node["extensions"]["EXT_mesh_gpu_instancing"];
      integer_values(ext.is_object() && ext.contains("attributes") ? ext["attributes"] : json(), e + ".EXT_mesh_gpu_instancing.attributes");
    }
  });
  each_object(doc, "textures", "", [&](const json& t, const std::string& e) {
    check_index_member(t, "source", e), check_index_member(t, "sampler", e);
    if (t.contains("extensions") && !t["extensions"].is_object()) fail(e, "extensions is not an object");
    if (t.contains("extensions"))
      for (const auto& [name, ext] : t["extensions"].items())
        if (ext.is_object()) check_index_member(ext, "source", e + ".extensions." + name);
  });
  each_object(doc, "accessors", "", [&](const json& a, const std::string& e) {
    check_index_member(a, "bufferView", e);
    if (!a.contains("sparse")) return;
    const json& sparse = a["sparse"];
    for (const char* part : {"indices", "values"})
      if (!sparse.is_object() || !sparse.contains(part) || !sparse[part].is_object() || !sparse[part].contains("bufferView") ||
          !sparse[part]["bufferView"].is_number_integer())
        fail(e, "sparse.{}.bufferView is not an integer index", part);
  });
  each_object(doc, "materials", "", [](const json&, const std::string&) {});
  each_object(doc, "samplers", "", [](const json&, const std::string&) {});
  each_object(doc, "scenes", "", [](const json&, const std::string&) {});
}

/// Every buffer view's buffer and byte range, checked once (the writer copies views that nothing read).
void GltfReader::check_buffer_views() const {
  const json& views = array("bufferViews");
  for (size_t i = 0; i < views.size(); ++i) {
    const std::string element = fmt::format("bufferViews[{}]", i);
    const json& view = item("bufferViews", int64_t(i), element);
    const int64_t buffer = index_in(view, "buffer", "buffers", element);
    if (buffer < 0) fail(element, "has no buffer");
    const uint64_t offset = unsigned_of(view, "byteOffset", 0, element), length = unsigned_of(view, "byteLength", 0, element);
    const std::string_view data = doc_->buffers[size_t(buffer)];
    if (length == 0) fail(element, "byteLength missing or 0");
    if (offset > data.size() || length > data.size() - offset)
      fail(element, "bytes {}..{} lie beyond buffer {}'s {} bytes", offset, offset + length, buffer, data.size());
  }
}

void GltfReader::load_images() {
  const json& images = array("images");
  for (size_t i = 0; i < images.size(); ++i) {
    const std::string element = fmt::format("images[{}]", i);
    const json& image = item("images", int64_t(i), element);
    const auto uri = image.find("uri");
    if (uri != image.end()) {
      if (!uri->is_string()) fail(element, "uri is not a string");
      doc_->images.push_back(bytes_of_uri(uri->get<std::string>(), element));
      continue;
    }
    const int64_t v = index_in(image, "bufferView", "bufferViews", element);
    if (v < 0) fail(element, "has neither uri nor bufferView");
    const json& view = item("bufferViews", v, element);
    const std::string view_element = fmt::format("bufferViews[{}]", v);
    const int64_t buffer = index_in(view, "buffer", "buffers", view_element);
    if (buffer < 0) fail(view_element, "has no buffer");
    const uint64_t offset = unsigned_of(view, "byteOffset", 0, view_element), length = unsigned_of(view, "byteLength", 0, view_element);
    const std::string_view data = doc_->buffers[size_t(buffer)];
    if (offset > data.size() || length > data.size() - offset)
      fail(view_element, "bytes {}..{} lie beyond buffer {}'s {} bytes", offset, offset + length, buffer, data.size());
    doc_->images.push_back(data.substr(size_t(offset), size_t(length)));  // a view: no copy per image
  }
}

AccessorView GltfReader::accessor(int64_t index, const std::string& element) const {
  const std::string a_element = fmt::format("accessors[{}]", index);
  const json& a = item("accessors", index, element);
  if (a.contains("sparse")) fail(a_element, "sparse accessors are not supported");
  AccessorView v;
  const auto type = a.find("type");
  v.components = type != a.end() && type->is_string() ? gltf_type_components(type->get<std::string>()) : 0;
  if (v.components == 0) fail(a_element, "type missing or not SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3 or MAT4");
  const auto ct = a.find("componentType");
  v.component_type = ct != a.end() && ct->is_number_integer() ? ct->get<int64_t>() : 0;
  const size_t component_size = gltf_component_size(v.component_type);
  if (component_size == 0) fail(a_element, "componentType missing or not one of 5120..5126 (except 5124)");
  v.normalized = a.value("normalized", false);
  v.count = size_t(unsigned_of(a, "count", 0, a_element));
  if (v.count == 0) fail(a_element, "count missing or 0");
  const int64_t view_index = index_in(a, "bufferView", "bufferViews", a_element);
  if (view_index < 0) fail(a_element, "has no bufferView (an all-zero accessor is not supported)");
  const std::string view_element = fmt::format("bufferViews[{}]", view_index);
  const json& view = item("bufferViews", view_index, a_element);
  if (view.contains("extensions") && view["extensions"].contains("EXT_meshopt_compression"))
    fail(view_element, "EXT_meshopt_compression is not supported");
  const int64_t buffer = index_in(view, "buffer", "buffers", view_element);
  if (buffer < 0) fail(view_element, "has no buffer");
  const uint64_t view_offset = unsigned_of(view, "byteOffset", 0, view_element);
  const uint64_t view_length = unsigned_of(view, "byteLength", 0, view_element);
  const std::string_view data = doc_->buffers[size_t(buffer)];
  if (view_offset > data.size() || view_length > data.size() - view_offset)
    fail(view_element, "bytes {}..{} lie beyond buffer {}'s {} bytes", view_offset, view_offset + view_length, buffer, data.size());
  const uint64_t element_size = component_size * v.components;
  const uint64_t stride = unsigned_of(view, "byteStride", element_size, view_element);
  if (stride < element_size || stride > 252) fail(view_element, "byteStride {} is not in {}..252 for {}", stride, element_size, a_element);
  const uint64_t offset = unsigned_of(a, "byteOffset", 0, a_element);
  // count <= 2^64 / stride is checked first, so the product cannot wrap.
  if (offset > view_length || uint64_t(v.count - 1) > (view_length - offset) / stride ||
      offset + uint64_t(v.count - 1) * stride + element_size > view_length)
    fail(a_element, "{} elements of {} bytes, {} apart from byte {}, do not fit bufferView {}'s {} bytes", v.count, element_size, stride,
         offset, view_index, view_length);
  v.stride = size_t(stride);
  v.data = reinterpret_cast<const unsigned char*>(data.data()) + view_offset + offset;
  return v;
}

AccessorView GltfReader::attribute(const json& primitive, const std::string& name, const std::string& element, bool required) const {
  const json& attributes = primitive.at("attributes");
  const auto it = attributes.find(name);
  if (it == attributes.end()) {
    if (required) fail(element, "has no {} attribute", name);
    return {};
  }
  if (!it->is_number_integer()) fail(element, "attribute {} is not an accessor index", name);
  return accessor(it->get<int64_t>(), fmt::format("{}.attributes.{}", element, name));
}

/// `count` numbers of node member `key`, checked.
std::vector<double> GltfReader::numbers_of(const json& node, const char* key, size_t count, const std::string& element) const {
  const json& a = node[key];
  if (!a.is_array() || a.size() != count) fail(element, "{} is not {} numbers", key, count);
  std::vector<double> v;
  for (const json& x : a) {
    if (!x.is_number() || !std::isfinite(x.get<double>())) fail(element, "{} is not {} finite numbers", key, count);
    v.push_back(x.get<double>());
  }
  return v;
}

/// A node's local transform: its `matrix` (column-major), or translation * rotation * scale.
Eigen::Matrix4d GltfReader::node_matrix(const json& node, const std::string& element) const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (node.contains("matrix")) {
    const std::vector<double> a = numbers_of(node, "matrix", 16, element);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m(r, c) = a[size_t(4 * c + r)];
    return m;
  }
  if (node.contains("scale")) {
    const std::vector<double> s = numbers_of(node, "scale", 3, element);
    m.topLeftCorner<3, 3>() = Eigen::Vector3d(s[0], s[1], s[2]).asDiagonal();
  }
  if (node.contains("rotation")) {
    const std::vector<double> q = numbers_of(node, "rotation", 4, element);
    const Eigen::Quaterniond rotation(q[3], q[0], q[1], q[2]);
    if (!(rotation.norm() > 0)) fail(element, "rotation is not a unit quaternion");
    // As stored, not normalized: a renderer builds its matrix from the stored values, and an exporter's
    // quaternion is unit only to float precision; normalizing moves world positions by a float step.
    m.topLeftCorner<3, 3>() = rotation.toRotationMatrix() * m.topLeftCorner<3, 3>();
  }
  if (node.contains("translation")) {
    const std::vector<double> t = numbers_of(node, "translation", 3, element);
    m.topRightCorner<3, 1>() = Eigen::Vector3d(t[0], t[1], t[2]);
  }
  return m;
}

/// Every node the scene reaches that shows a mesh, in the order its node tree reaches them, with its
/// world transform: the default scene, else scene 0, else every root node.
std::vector<MeshInstance> GltfReader::scene_instances() const {
  const json& nodes = array("nodes");
  std::vector<int64_t> roots;
  const json& scenes = array("scenes");
  int64_t scene = -1;
  if (doc_->json.contains("scene"))
    scene = index_in(doc_->json, "scene", "scenes", "scene");
  else if (!scenes.empty())
    scene = 0;
  if (scene >= 0) {
    const json& s = item("scenes", scene, "scene");
    const std::string element = fmt::format("scenes[{}]", scene);
    if (s.contains("nodes"))
      for (const json& n : s["nodes"]) {
        if (!n.is_number_integer()) fail(element, "nodes holds a non-integer");
        roots.push_back(n.get<int64_t>());
      }
  } else {
    std::vector<bool> is_child(nodes.size(), false);
    for (const json& n : nodes)
      if (n.is_object() && n.contains("children") && n["children"].is_array())
        for (const json& c : n["children"])
          if (c.is_number_integer() && c.get<int64_t>() >= 0 && size_t(c.get<int64_t>()) < nodes.size())
            is_child[size_t(c.get<int64_t>())] = true;
    for (size_t i = 0; i < nodes.size(); ++i)
      if (!is_child[i]) roots.push_back(int64_t(i));
  }
  std::vector<bool> visited(nodes.size(), false);
  std::vector<MeshInstance> instances;
  std::vector<std::pair<int64_t, Eigen::Matrix4d>> stack;  // node, its parent's world transform
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, Eigen::Matrix4d::Identity()});
  while (!stack.empty()) {
    const auto [n, parent] = stack.back();
    stack.pop_back();
    const json& node = item("nodes", n, "scene's node tree");
    if (visited[size_t(n)]) fail(fmt::format("nodes[{}]", n), "is reached twice (a node has one parent, the tree no cycle)");
    visited[size_t(n)] = true;
    const std::string element = fmt::format("nodes[{}]", n);
    const Eigen::Matrix4d world = parent * node_matrix(node, element);
    const int64_t m = index_in(node, "mesh", "meshes", element);
    if (m >= 0) instances.push_back({size_t(m), world});
    if (node.contains("children")) {
      if (!node["children"].is_array()) fail(element, "children is not an array");
      const json& children = node["children"];
      for (auto it = children.rbegin(); it != children.rend(); ++it) {
        if (!it->is_number_integer()) fail(element, "children holds a non-integer");
        stack.push_back({it->get<int64_t>(), world});
      }
    }
  }
  return instances;
}

/// Per mesh of the document, the area the scene shows of it in units of its own area: the sum of its
/// instances' area scales, |det|^(2/3) of each world transform (exact for a uniform scale).
std::vector<double> area_scales(const std::vector<MeshInstance>& instances, size_t meshes) {
  std::vector<double> scale(meshes, 0.0);
  for (const MeshInstance& i : instances) scale[i.mesh] += std::pow(std::abs(i.world.topLeftCorner<3, 3>().determinant()), 2.0 / 3.0);
  return scale;
}

/// The meshes `instances` show, each once, in the order of their first instance.
std::vector<size_t> meshes_of(const std::vector<MeshInstance>& instances) {
  std::vector<size_t> meshes;
  for (const MeshInstance& i : instances)
    if (std::find(meshes.begin(), meshes.end(), i.mesh) == meshes.end()) meshes.push_back(i.mesh);
  return meshes;
}

/// Appends instance `i`'s copy of `local`'s triangles [t0, t1) and vertices [v0, v1) to `out`, in world
/// space: positions through the transform, normals through its inverse transpose, tangents through it
/// (their handedness with its determinant's sign). A mirroring transform (negative determinant) turns
/// the front faces, as glTF renders them: corners 1 and 2 swap so the world-space winding shows the same side.
void append_instance(const TexturedMesh& local, size_t t0, size_t t1, size_t v0, size_t v1, const MeshInstance& instance, uint32_t i,
                     TexturedMesh& out, std::vector<uint32_t>& triangle_primitive, std::vector<uint32_t>& vertex_source,
                     const GltfDocument& doc) {
  const Eigen::Matrix3d linear = instance.world.topLeftCorner<3, 3>();
  const Eigen::Matrix3d normal_matrix = linear.inverse().transpose();
  const bool mirrored = linear.determinant() < 0;
  const uint32_t base = uint32_t(out.positions.size());
  for (size_t v = v0; v < v1; ++v) {
    out.positions.push_back((instance.world * as_eigen(local.positions[v]).homogeneous()).head<3>());
    vertex_source.push_back(doc.vertex_source[v]);
  }
  auto direction = [](const Eigen::Matrix3d& m, const Vec3& d) {
    const Vec3 x = m * as_eigen(d);
    return x.norm() > 0 ? Vec3(x.normalized()) : x;
  };
  for (size_t t = t0; t < t1; ++t) {
    const std::array<size_t, 3> corner = mirrored ? std::array<size_t, 3>{0, 2, 1} : std::array<size_t, 3>{0, 1, 2};
    Tri tri;
    for (size_t k = 0; k < 3; ++k) tri[k] = base + uint32_t(local.triangles[t][corner[k]] - v0);
    out.triangles.push_back(tri);
    out.face_material.push_back(local.face_material[t]);
    out.source_mesh.push_back(i);
    triangle_primitive.push_back(doc.triangle_primitive[t]);
    for (const size_t k : corner) {
      const size_t c = 3 * t + k;
      out.corner_uv.push_back(local.corner_uv[c]);
      if (!local.corner_normal.empty()) out.corner_normal.push_back(direction(normal_matrix, local.corner_normal[c]));
      if (!local.corner_color.empty()) out.corner_color.push_back(local.corner_color[c]);
      if (!local.corner_tangent.empty()) {
        const Vec4& tg = local.corner_tangent[c];
        const Vec3 d = direction(linear, tg.head<3>());
        out.corner_tangent.push_back(Vec4(d, mirrored ? -tg.w() : tg.w()));
      }
    }
  }
}

/// `local` (each mesh once, as read) with every instance in world space (append_instance); source_mesh
/// is the instance.
TexturedMesh GltfReader::flattened(const TexturedMesh& local, const std::vector<MeshInstance>& instances) const {
  // Each mesh's triangles and vertices are contiguous in `local` (read mesh by mesh).
  std::map<size_t, std::array<size_t, 4>> range;  // mesh -> t0, t1, v0, v1
  for (size_t t = 0; t < local.num_triangles();) {
    const uint32_t m = local.source_mesh[t];
    size_t end = t;
    uint32_t v0 = UINT32_MAX, v1 = 0;
    for (; end < local.num_triangles() && local.source_mesh[end] == m; ++end)
      for (uint32_t v : local.triangles[end]) v0 = std::min(v0, v), v1 = std::max(v1, v + 1);
    range[m] = {t, end, v0, v1};
    t = end;
  }
  uint64_t total = 0;
  for (const MeshInstance& i : instances)
    if (range.count(i.mesh)) total += range[i.mesh][1] - range[i.mesh][0];
  if (total > kMaxFlattenedTriangles)
    fail("scene",
         "its {} mesh instances hold {} triangles in world space, more than tightex flattens ({}); write glTF to keep them instanced",
         instances.size(), total, kMaxFlattenedTriangles);
  TexturedMesh out;
  out.materials = local.materials, out.textures = local.textures;
  std::vector<uint32_t> triangle_primitive, vertex_source;
  for (size_t i = 0; i < instances.size(); ++i) {
    const auto it = range.find(instances[i].mesh);
    if (it == range.end()) continue;  // a mesh of points or lines only
    const auto [t0, t1, v0, v1] = it->second;
    append_instance(local, t0, t1, v0, v1, instances[i], uint32_t(i), out, triangle_primitive, vertex_source, *doc_);
  }
  doc_->triangle_primitive = std::move(triangle_primitive);
  doc_->vertex_source = std::move(vertex_source);
  doc_->flattened = true;
  return out;
}

/// Refuses what a triangle primitive carries that cannot follow new vertices.
void GltfReader::check_supported(const json& primitive, const std::string& element) const {
  if (primitive.contains("extensions")) {
    const json& ext = primitive["extensions"];
    if (ext.contains("KHR_draco_mesh_compression")) fail(element, "KHR_draco_mesh_compression is not supported");
  }
  if (primitive.contains("targets") && !primitive["targets"].empty())
    fail(element, "has morph targets, which cannot follow the vertices tightex splits at the new seams (not supported)");
  if (!primitive.contains("attributes") || !primitive["attributes"].is_object()) fail(element, "attributes missing");
  for (const auto& [name, value] : primitive["attributes"].items())
    if (name.rfind("JOINTS_", 0) == 0 || name.rfind("WEIGHTS_", 0) == 0)
      fail(element, "is skinned ({}), which tightex does not carry over (not supported)", name);
}

/// The primitive's triangles as vertex indices into its own attributes: a list, strip or fan.
std::vector<Tri> GltfReader::primitive_triangles(const json& primitive, size_t vertices, int64_t mode, const std::string& element) const {
  std::vector<uint32_t> index;
  if (primitive.contains("indices")) {
    if (!primitive["indices"].is_number_integer()) fail(element, "indices is not an accessor index");
    const AccessorView v = accessor(primitive["indices"].get<int64_t>(), element + ".indices");
    if (v.components != 1 || v.normalized ||
        (v.component_type != kUnsignedByte && v.component_type != kUnsignedShort && v.component_type != kUnsignedInt))
      fail(element, "indices are not SCALAR unsigned byte, short or int");
    index.resize(v.count);
    for (size_t i = 0; i < v.count; ++i) {
      const double x = v.get(i, 0);
      if (x >= double(vertices)) fail(element, "index {} (entry {}) is out of range ({} vertices)", x, i, vertices);
      index[i] = uint32_t(x);
    }
  } else {
    if (vertices > UINT32_MAX) fail(element, "too many vertices");
    index.resize(vertices);
    for (size_t i = 0; i < vertices; ++i) index[i] = uint32_t(i);
  }
  std::vector<Tri> tris;
  if (mode == 4) {
    if (index.size() % 3 != 0) fail(element, "{} indices are not a whole number of triangles", index.size());
    for (size_t i = 0; i + 2 < index.size(); i += 3) tris.push_back({index[i], index[i + 1], index[i + 2]});
  } else if (mode == 5) {  // strip: every other triangle reversed, so all keep the first one's winding
    for (size_t i = 0; i + 2 < index.size(); ++i)
      tris.push_back(i % 2 == 0 ? Tri{index[i], index[i + 1], index[i + 2]} : Tri{index[i + 1], index[i], index[i + 2]});
  } else {  // fan
    for (size_t i = 1; i + 1 < index.size(); ++i) tris.push_back({index[i], index[i + 1], index[0]});
  }
  if (tris.empty()) fail(element, "has no triangle");
  return tris;
}

const json* base_color_info(const json& materials, int material);

/// The TexturedMesh texture of a texture info (baseColorTexture, normalTexture, ...), made on first use
/// for its image (one image bound to two slots is one texture).
int GltfReader::texture_for(const json& info, const std::string& t_element, ReadState& state) {
  if (!info.is_object()) fail(t_element, "is not an object");
  const int64_t tex = index_in(info, "index", "textures", t_element);
  if (tex < 0) fail(t_element, "has no index");
  const json& texture = array("textures")[size_t(tex)];
  const std::string element = fmt::format("textures[{}]", tex);
  int64_t image = index_in(texture, "source", "images", element);
  // WebP tightex decodes; KTX2 (Basis Universal) and DDS it does not: their fallback source is read.
  if (texture.contains("extensions") && texture["extensions"].is_object())
    for (const char* ext : {"EXT_texture_webp", "KHR_texture_basisu", "MSFT_texture_dds"}) {
      if (!texture["extensions"].contains(ext) || !texture["extensions"][ext].is_object()) continue;
      const bool decoded = std::string_view(ext) == "EXT_texture_webp";
      if (!decoded && image < 0)
        fail(element, "{} images ({}) are not supported, and the texture has no PNG, JPEG or WebP fallback source", ext,
             std::string_view(ext) == "KHR_texture_basisu" ? "KTX2" : "DDS");
      if (!decoded && state.fallbacks_noted.insert(tex).second)
        warnings_.push_back(fmt::format("{}: {} image not decoded: its fallback source images[{}] is read", element, ext, image));
      if (decoded && image < 0) image = index_in(texture["extensions"][ext], "source", "images", element + ".extensions." + ext);
    }
  if (image < 0) fail(element, "has no image source tightex can read");
  auto [it, inserted] = state.texture_of.try_emplace(int(image), int(state.mesh.textures.size()));
  if (inserted) {
    const json& img = array("images")[size_t(image)];
    Texture t;
    t.path = img.contains("uri") && img["uri"].is_string() && img["uri"].get<std::string>().rfind("data:", 0) != 0
                 ? (folder_ / with_forward_slashes(percent_decoded(img["uri"].get<std::string>()))).lexically_normal().string()
                 : fmt::format("{}_image{}", fs::path(path_).stem().string(), image);
    state.mesh.textures.push_back(std::move(t));
    doc_->texture_image.push_back(int(image));
  }
  return it->second;
}

/// The UV set and KHR_texture_transform a texture info reads through (texCoord 0 and no transform by
/// default): two slots with the same read the same texture coordinates.
std::pair<int64_t, json> uv_source(const json* info) {
  if (info == nullptr || !info->is_object()) return {0, json()};
  int64_t set = info->contains("texCoord") && (*info)["texCoord"].is_number_integer() ? (*info)["texCoord"].get<int64_t>() : 0;
  json transform;
  if (info->contains("extensions") && (*info)["extensions"].is_object() && (*info)["extensions"].contains("KHR_texture_transform")) {
    transform = (*info)["extensions"]["KHR_texture_transform"];
    if (transform.is_object() && transform.contains("texCoord") && transform["texCoord"].is_number_integer())
      set = transform["texCoord"].get<int64_t>();
    if (transform.is_object()) transform.erase("texCoord");
    if (transform.is_object() && transform.empty()) transform = json();
  }
  return {set, transform};
}

/// The material's other maps (MaterialSlot, kGltfSlots: the core slots and the KHR_materials_* ones)
/// that read the same texture coordinates as its base colour. A map on another UV set or under another
/// transform is left out (write_gltf removes it, saying so).
void GltfReader::read_map_slots(const json& g, const json* base, const std::string& element, ReadState& state, Material& m) {
  const auto base_source = uv_source(base);
  for (const GltfSlot& slot : kGltfSlots) {
    const json* holder = gltf_slot_holder(g, slot);
    if (holder == nullptr || !holder->contains(slot.key)) continue;
    const json& info = (*holder)[slot.key];
    if (uv_source(&info) != base_source) continue;
    const std::string where = std::string(slot.holder).rfind("KHR_", 0) == 0 ? ".extensions." + std::string(slot.holder) + "."
                              : *slot.holder != '\0'                         ? "." + std::string(slot.holder) + "."
                                                                             : std::string(".");
    m.maps[size_t(slot.slot)] = texture_for(info, element + where + slot.key, state);
  }
}

namespace {

/// The number `key` of `holder` (null: absent), or `fallback`; a member that is not a number is refused.
double factor_of(const json* holder, const char* key, double fallback, const std::string& element) {
  if (holder == nullptr || !holder->is_object() || !holder->contains(key)) return fallback;
  const json& v = (*holder)[key];
  if (!v.is_number() || !std::isfinite(v.get<double>())) fail_input("{}: {} is not a finite number", element, key);
  return v.get<double>();
}

/// The colour `key` (3 numbers) of `holder` in the first three channels of `fallback`, or `fallback`.
SlotFactor colour_of(const json* holder, const char* key, const SlotFactor& fallback, const std::string& element) {
  if (holder == nullptr || !holder->is_object() || !holder->contains(key)) return fallback;
  const json& v = (*holder)[key];
  if (!v.is_array() || v.size() != 3) fail_input("{}: {} is not 3 numbers", element, key);
  SlotFactor f = fallback;
  for (size_t k = 0; k < 3; ++k) {
    if (!v[k].is_number() || !std::isfinite(v[k].get<double>())) fail_input("{}: {} is not 3 numbers", element, key);
    f[k] = v[k].get<double>();
  }
  return f;
}

/// The extension `name` of material `g`, or null.
const json* extension_of(const json& g, const char* name) {
  const auto e = g.find("extensions");
  if (e == g.end() || !e->is_object()) return nullptr;
  const auto x = e->find(name);
  return x != e->end() && x->is_object() ? &*x : nullptr;
}

/// Every slot's factor of glTF material `g` (Material::factor): what a viewer multiplies the slot's
/// texels by, and shows alone without a texture; glTF's defaults where the material says none.
std::array<SlotFactor, kMaterialSlots> slot_factors(const json& g, const std::string& element) {
  std::array<SlotFactor, kMaterialSlots> f = default_slot_factors();
  auto at = [&](MaterialSlot s) -> SlotFactor& { return f[size_t(s)]; };
  auto one = [](double x) { return SlotFactor{x, x, x, x}; };
  const json* pbr = g.contains("pbrMetallicRoughness") && g["pbrMetallicRoughness"].is_object() ? &g["pbrMetallicRoughness"] : nullptr;
  at(MaterialSlot::kMetallicRoughness) = {1, factor_of(pbr, "roughnessFactor", 1, element), factor_of(pbr, "metallicFactor", 1, element),
                                          1};
  const json* occlusion = g.contains("occlusionTexture") ? &g["occlusionTexture"] : nullptr;
  at(MaterialSlot::kOcclusion) = one(factor_of(occlusion, "strength", 1, element + ".occlusionTexture"));
  const double strength = factor_of(extension_of(g, "KHR_materials_emissive_strength"), "emissiveStrength", 1, element);
  at(MaterialSlot::kEmissive) = colour_of(&g, "emissiveFactor", {0, 0, 0, 1}, element);
  for (size_t k = 0; k < 3; ++k) at(MaterialSlot::kEmissive)[k] *= strength;
  const json* normal = g.contains("normalTexture") ? &g["normalTexture"] : nullptr;
  at(MaterialSlot::kNormal) = one(factor_of(normal, "scale", 1, element + ".normalTexture"));
  const json* specular = extension_of(g, "KHR_materials_specular");
  at(MaterialSlot::kSpecularStrength) = one(factor_of(specular, "specularFactor", 1, element));
  at(MaterialSlot::kSpecular) = colour_of(specular, "specularColorFactor", {1, 1, 1, 1}, element);
  const json* clearcoat = extension_of(g, "KHR_materials_clearcoat");
  at(MaterialSlot::kClearcoat) = one(factor_of(clearcoat, "clearcoatFactor", 0, element));
  at(MaterialSlot::kClearcoatRoughness) = one(factor_of(clearcoat, "clearcoatRoughnessFactor", 0, element));
  const json* sheen = extension_of(g, "KHR_materials_sheen");
  at(MaterialSlot::kSheenColour) = colour_of(sheen, "sheenColorFactor", {0, 0, 0, 1}, element);
  at(MaterialSlot::kSheenRoughness) = one(factor_of(sheen, "sheenRoughnessFactor", 0, element));
  at(MaterialSlot::kTransmission) = one(factor_of(extension_of(g, "KHR_materials_transmission"), "transmissionFactor", 0, element));
  at(MaterialSlot::kThickness) = one(factor_of(extension_of(g, "KHR_materials_volume"), "thicknessFactor", 0, element));
  at(MaterialSlot::kIridescence) = one(factor_of(extension_of(g, "KHR_materials_iridescence"), "iridescenceFactor", 0, element));
  at(MaterialSlot::kAnisotropy) = {1, 1, factor_of(extension_of(g, "KHR_materials_anisotropy"), "anisotropyStrength", 0, element), 1};
  return f;
}

}  // namespace

/// The TexturedMesh material of glTF material `material` (-1: the default one), made on first use with
/// its base colour texture and factor.
int32_t GltfReader::material_for(int material, ReadState& state) {
  const auto found = state.material_of.find(material);
  if (found != state.material_of.end()) return found->second;
  Material m;
  m.name = fmt::format("material_{}", material);
  if (material >= 0) {
    const json& g = array("materials")[size_t(material)];
    if (g.contains("name") && g["name"].is_string()) m.name = g["name"].get<std::string>();
    const std::string element = fmt::format("materials[{}]", material);
    const json pbr = g.value("pbrMetallicRoughness", json::object());
    if (pbr.contains("baseColorFactor")) {
      const json& f = pbr["baseColorFactor"];
      if (!f.is_array() || f.size() != 4) fail(element, "baseColorFactor is not 4 numbers");
      for (int k = 0; k < 3; ++k) {
        if (!f[size_t(k)].is_number()) fail(element, "baseColorFactor is not 4 numbers");
        m.kd[size_t(k)] = f[size_t(k)].get<double>();
      }
    }
    const json* base = base_color_info(array("materials"), material);
    if (base != nullptr) m.texture = texture_for(*base, element + ".pbrMetallicRoughness.baseColorTexture", state);
    read_map_slots(g, base, element, state, m);
    m.factor = slot_factors(g, element);
  }
  m.kd_multiplies_texture = true;
  const int32_t index = int32_t(state.mesh.materials.size());
  state.mesh.materials.push_back(std::move(m));
  state.material_of[material] = index;
  return index;
}

/// The texture info of a material's base colour, or null.
const json* base_color_info(const json& materials, int material) {
  if (material < 0) return nullptr;
  const json& g = materials[size_t(material)];
  const auto pbr = g.find("pbrMetallicRoughness");
  if (pbr == g.end() || !pbr->is_object() || !pbr->contains("baseColorTexture")) return nullptr;
  return &(*pbr)["baseColorTexture"];
}

/// The base colour texture's sampler wrapS and wrapT (REPEAT when it has none).
std::array<int64_t, 2> GltfReader::sampler_wrap(const json& info) const {
  std::array<int64_t, 2> wrap{kRepeat, kRepeat};
  const json& texture = array("textures")[size_t(info["index"].get<int64_t>())];
  const int64_t sampler = index_in(texture, "sampler", "samplers", "texture");
  if (sampler < 0) return wrap;
  const json& s = array("samplers")[size_t(sampler)];
  wrap[0] = int64_t(unsigned_of(s, "wrapS", kRepeat, fmt::format("samplers[{}]", sampler)));
  wrap[1] = int64_t(unsigned_of(s, "wrapT", kRepeat, fmt::format("samplers[{}]", sampler)));
  return wrap;
}

/// Reads a 2-number array of KHR_texture_transform (offset, scale), or the default.
std::array<double, 2> pair_of(const json& t, const char* key, double fallback) {
  std::array<double, 2> v{fallback, fallback};
  if (t.contains(key) && t[key].is_array() && t[key].size() == 2 && t[key][0].is_number() && t[key][1].is_number())
    v = {t[key][0].get<double>(), t[key][1].get<double>()};
  return v;
}

/// KHR_texture_transform's offset + R * S * uv, R turning u towards -v by `rotation` radians: the
/// direction the extension's TextureTransformTest marks correct and three.js draws (its GLSL, read
/// column-major, turns the other way, which that test marks as the error).
Vec2 transformed_uv(double u, double v, const std::array<double, 2>& offset, double rotation, const std::array<double, 2>& scale) {
  const double su = scale[0] * u, sv = scale[1] * v;
  if (rotation == 0) return Vec2(offset[0] + su, offset[1] + sv);
  const double c = std::cos(rotation), s = std::sin(rotation);
  return Vec2(offset[0] + c * su + s * sv, offset[1] - s * su + c * sv);
}

/// Corner UVs of the primitive's triangles, in tightex's convention (v up): the UV set the base colour
/// texture uses, with its KHR_texture_transform applied (offset + rotation * scale * uv, the rotation
/// turning u towards -v as glTF viewers draw it), so the corner UVs are what the renderer samples;
/// TEXCOORD_0 (or zero) without a texture. Returns the name of the set read.
std::string GltfReader::read_corner_uvs(const json& primitive, int material, const std::vector<Tri>& tris, size_t n,
                                        const std::string& element, ReadState& state) {
  const json* info = base_color_info(array("materials"), material);
  int64_t set = info != nullptr ? int64_t(unsigned_of(*info, "texCoord", 0, element + " material's baseColorTexture")) : 0;
  std::array<double, 2> offset{0, 0}, scale{1, 1};
  double rotation = 0;
  if (info != nullptr && info->contains("extensions") && (*info)["extensions"].contains("KHR_texture_transform")) {
    const json& t = (*info)["extensions"]["KHR_texture_transform"];
    if (!t.is_object()) fail(element, "its material's KHR_texture_transform is not an object");
    if (t.contains("rotation") && !t["rotation"].is_number())
      fail(element, "its material's KHR_texture_transform rotation is not a number");
    rotation = t.value("rotation", 0.0);
    offset = pair_of(t, "offset", 0.0), scale = pair_of(t, "scale", 1.0);
    if (t.contains("texCoord")) set = int64_t(unsigned_of(t, "texCoord", 0, element + " KHR_texture_transform"));
  }
  const std::string name = fmt::format("TEXCOORD_{}", set);
  const AccessorView uv = attribute(primitive, name, element, false);
  if (info != nullptr && uv.data == nullptr) fail(element, "its base colour texture uses {}, which the primitive does not have", name);
  if (uv.data != nullptr) {
    if (uv.components != 2 || !attribute_type_allowed("TEXCOORD", uv.component_type, uv.normalized, quantized_))
      fail(element, "{} is not VEC2 float or normalized unsigned byte/short{}", name,
           quantized_ ? " or an 8/16-bit integer type (KHR_mesh_quantization)" : "");
    if (uv.count != n) fail(element, "{} has {} entries for {} positions", name, uv.count, n);
  }
  const std::array<int64_t, 2> wrap = info != nullptr ? sampler_wrap(*info) : std::array<int64_t, 2>{kRepeat, kRepeat};
  for (const Tri& t : tris)
    for (const uint32_t v : t) {
      Vec2 g(0, 0);
      if (uv.data != nullptr) g = transformed_uv(uv.get(v, 0), uv.get(v, 1), offset, rotation, scale);
      if (!std::isfinite(g.x()) || !std::isfinite(g.y())) fail(element, "{} entry {} is not finite", name, v);
      for (int k = 0; k < 2; ++k)
        if (wrap[size_t(k)] != kRepeat && (g[k] < -kWrapSlack || g[k] > 1 + kWrapSlack))
          fail(element,
               "{} entry {} ({}) lies outside [0,1] under its sampler's wrap mode {}, which tightex does not bake (it reads as REPEAT)",
               name, v, g[k], wrap[size_t(k)]);
      state.mesh.corner_uv.push_back(Vec2(g.x(), 1.0 - g.y()));
    }
  return name;
}

/// The primitive's attributes that write_gltf copies unchanged: all but POSITION, NORMAL, TANGENT
/// (written anew), TEXCOORD_0 and `uv_set` (the new coordinates take TEXCOORD_0), and COLOR_0 where
/// `colours_baked` (the new texture holds it). Each must have `n` elements; one without a bufferView
/// is all zeros.
std::vector<GltfVertexAttribute> GltfReader::carried_attributes(const json& primitive, const std::string& uv_set, bool colours_baked,
                                                                size_t n, const std::string& element) const {
  std::vector<GltfVertexAttribute> carried;
  for (const auto& [name, value] : primitive.at("attributes").items()) {
    if (name == "POSITION" || name == "NORMAL" || name == "TANGENT" || name == "TEXCOORD_0" || name == uv_set ||
        (name == "COLOR_0" && colours_baked))
      continue;
    const std::string a_element = fmt::format("{}.attributes.{}", element, name);
    if (!value.is_number_integer()) fail(element, "attribute {} is not an accessor index", name);
    const json& a = item("accessors", value.get<int64_t>(), a_element);
    GltfVertexAttribute attribute;
    attribute.name = name;
    AccessorView view;
    if (a.contains("bufferView")) {
      view = accessor(value.get<int64_t>(), a_element);
    } else {  // all zeros: type and component type still checked
      view.components = a.contains("type") && a["type"].is_string() ? gltf_type_components(a["type"].get<std::string>()) : 0;
      view.component_type = a.contains("componentType") && a["componentType"].is_number_integer() ? a["componentType"].get<int64_t>() : 0;
      view.count = size_t(unsigned_of(a, "count", 0, a_element));
      if (view.components == 0 || gltf_component_size(view.component_type) == 0) fail(a_element, "type or componentType is not glTF's");
    }
    if (view.count != n) fail(element, "attribute {} has {} elements for {} positions", name, view.count, n);
    attribute.data = view.data, attribute.stride = view.stride;
    attribute.element_size = view.components * gltf_component_size(view.component_type);
    attribute.component_type = view.component_type;
    attribute.type = a["type"].get<std::string>();
    attribute.normalized = a.value("normalized", false);
    carried.push_back(std::move(attribute));
  }
  return carried;
}

/// Fails on the first of the `used` entries of accessor `a` (if present) with a component that is not
/// finite.
void GltfReader::check_finite_entries(const std::vector<uint32_t>& used, const AccessorView& a, const char* name,
                                      const std::string& element) const {
  if (a.data == nullptr) return;
  for (const uint32_t v : used)
    for (size_t k = 0; k < a.components; ++k)
      if (!std::isfinite(a.get(v, k))) fail(element, "{} entry {} is not finite", name, v);
}

void GltfReader::read_primitive(size_t m, size_t p, ReadState& state) {
  const std::string element = fmt::format("meshes[{}].primitives[{}]", m, p);
  const json& primitive = array("meshes")[m]["primitives"][p];
  if (!primitive.is_object()) fail(element, "is not an object");
  const int64_t mode = int64_t(unsigned_of(primitive, "mode", 4, element));
  if (mode > 6) fail(element, "mode {} is not a glTF primitive mode", mode);
  if (mode < 4) {  // points and lines: written back as they are
    not_read_.push_back(fmt::format("{} ({})", element, mode == 0 ? "points" : "lines"));
    return;
  }
  check_supported(primitive, element);
  const AccessorView pos = attribute(primitive, "POSITION", element, true);
  if (pos.components != 3 || !attribute_type_allowed("POSITION", pos.component_type, pos.normalized, quantized_))
    fail(element, "POSITION is not VEC3 float{}",
         quantized_ ? " or an 8/16-bit integer type (KHR_mesh_quantization)" : " (integer positions need KHR_mesh_quantization)");
  const std::vector<Tri> tris = primitive_triangles(primitive, pos.count, mode, element);
  // Primitives may share accessors, so what is read is bounded by the bytes read, not by each accessor.
  corners_read_ += 3 * uint64_t(tris.size());
  if (corners_read_ > kCornersPerInputByte * input_bytes_ + kCornerSlack)
    fail(element, "the primitives so far have {} corners from {} bytes of model and buffers (accessors shared by too many primitives)",
         corners_read_, input_bytes_);
  // Only the vertices its triangles use, each once (a vertex buffer shared by many primitives is not
  // copied for each).
  std::vector<uint32_t> used;
  used.reserve(3 * tris.size());
  for (const Tri& t : tris) used.insert(used.end(), t.begin(), t.end());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  const size_t base = state.mesh.positions.size();
  if (used.size() > size_t(UINT32_MAX) - base) fail(element, "too many vertices");
  for (const uint32_t i : used) {
    const Vec3 x(pos.get(i, 0), pos.get(i, 1), pos.get(i, 2));
    if (!x.allFinite() || x.cwiseAbs().maxCoeff() > kAbsurdCoordinate) fail(element, "POSITION entry {} is not a finite coordinate", i);
    state.mesh.positions.push_back(x);
    doc_->vertex_source.push_back(i);
  }
  const int material = int(index_in(primitive, "material", "materials", element));
  const int32_t tm = material_for(material, state);
  const std::string uv_set = read_corner_uvs(primitive, material, tris, pos.count, element, state);
  const AccessorView normal = attribute(primitive, "NORMAL", element, false);
  if (normal.data != nullptr && (normal.components != 3 || normal.count != pos.count ||
                                 !attribute_type_allowed("NORMAL", normal.component_type, normal.normalized, quantized_)))
    fail(element, "NORMAL is not VEC3 float{} with one entry per position", quantized_ ? " or normalized byte/short" : "");
  const AccessorView color = attribute(primitive, "COLOR_0", element, false);
  if (color.data != nullptr && ((color.components != 3 && color.components != 4) || color.count != pos.count ||
                                !(color.component_type == kFloat || color.normalized)))
    fail(element, "COLOR_0 is not VEC3/VEC4 float or normalized unsigned byte/short with one entry per position");
  const AccessorView tangent = attribute(primitive, "TANGENT", element, false);
  if (tangent.data != nullptr && (tangent.components != 4 || tangent.count != pos.count ||
                                  !attribute_type_allowed("TANGENT", tangent.component_type, tangent.normalized, quantized_)))
    fail(element, "TANGENT is not VEC4 float{} with one entry per position", quantized_ ? " or normalized byte/short" : "");
  state.any_tangents |= tangent.data != nullptr;
  state.any_normals |= normal.data != nullptr;
  state.any_colors |= color.data != nullptr;
  const uint32_t prim_index = uint32_t(doc_->primitives.size());
  // texture_vertex_colours bakes them, unless the material binds other maps (then its triangles keep
  // their own coordinates and are written as they came, COLOR_0 with them).
  const Material& read_material = state.mesh.materials[size_t(tm)];
  const bool colours_baked = base_color_info(array("materials"), material) == nullptr &&
                             std::all_of(read_material.maps.begin(), read_material.maps.end(), [](int map) { return map < 0; });
  doc_->primitives.push_back(
      {m, p, material, normal.data != nullptr, carried_attributes(primitive, uv_set, colours_baked, pos.count, element)});
  check_finite_entries(used, normal, "NORMAL", element);
  check_finite_entries(used, tangent, "TANGENT", element);
  check_finite_entries(used, color, "COLOR_0", element);
  // Each used vertex's new index: from a table over the accessor where the primitive uses a fair share
  // of it, else by binary search in `used` (many primitives sharing one large vertex buffer would
  // each fill a table of its size).
  std::vector<uint32_t> table;
  if (pos.count <= 4 * used.size() + 1024) {
    table.assign(pos.count, kNone);
    for (size_t k = 0; k < used.size(); ++k) table[used[k]] = uint32_t(base + k);
  }
  auto new_vertex = [&](uint32_t v) {
    return table.empty() ? uint32_t(base + size_t(std::lower_bound(used.begin(), used.end(), v) - used.begin())) : table[v];
  };
  // The corners' normals, tangents and colours are kept only once some primitive has them (the corners
  // before it get the defaults then): a scan without tangents or colours does not hold 48 bytes a corner
  // of zeros and ones.
  TexturedMesh& mesh = state.mesh;
  const size_t first = mesh.triangles.size(), corners = 3 * (first + tris.size());
  mesh.triangles.resize(first + tris.size());
  mesh.face_material.resize(first + tris.size(), tm);
  mesh.source_mesh.resize(first + tris.size(), uint32_t(m));
  doc_->triangle_primitive.resize(first + tris.size(), prim_index);
  const bool normals = grow_corner_attribute(mesh.corner_normal, normal.data != nullptr, corners, Vec3(0, 0, 0));
  grow_corner_attribute(state.corner_has_normal, normal.data != nullptr, corners, uint8_t(0));
  const bool tangents = grow_corner_attribute(mesh.corner_tangent, tangent.data != nullptr, corners, Vec4(0, 0, 0, 0));
  const bool colours = grow_corner_attribute(mesh.corner_color, color.data != nullptr, corners, std::array<float, 4>{1, 1, 1, 1});
  tbb::parallel_for(size_t(0), tris.size(), [&](size_t i) {
    const Tri& t = tris[i];
    mesh.triangles[first + i] = {new_vertex(t[0]), new_vertex(t[1]), new_vertex(t[2])};
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t v = t[k];
      const size_t c = 3 * (first + i) + k;
      if (normals) mesh.corner_normal[c] = Vec3(normal.get(v, 0), normal.get(v, 1), normal.get(v, 2)), state.corner_has_normal[c] = 1;
      if (tangents) mesh.corner_tangent[c] = Vec4(tangent.get(v, 0), tangent.get(v, 1), tangent.get(v, 2), tangent.get(v, 3));
      if (colours)
        for (size_t j = 0; j < color.components; ++j) {
          const double x = color.get(v, j);
          mesh.corner_color[c][j] = float(j < 3 ? linear_to_srgb(x) : std::clamp(x, 0.0, 1.0));
        }
    }
  });
}

/// Corners without a normal (a primitive without NORMAL beside one with) get their face's normal, as a
/// renderer shades them; none at all: no normals.
void GltfReader::finish_normals(ReadState& state) const {
  TexturedMesh& mesh = state.mesh;
  if (!state.any_normals) {
    mesh.corner_normal.clear();
    return;
  }
  for (size_t t = 0; t < mesh.num_triangles(); ++t) {
    const Tri& tri = mesh.triangles[t];
    Vec3 n = (mesh.positions[tri[1]] - mesh.positions[tri[0]]).cross(mesh.positions[tri[2]] - mesh.positions[tri[0]]);
    n = n.norm() > 0 ? Vec3(n.normalized()) : Vec3(0, 0, 1);
    for (size_t k = 0; k < 3; ++k)
      if (!state.corner_has_normal[3 * t + k]) mesh.corner_normal[3 * t + k] = n;
  }
}

/// The header size of every texture, and with load_textures its pixels (load_texture_pixels, from the
/// document the mesh keeps).
void GltfReader::load_textures(TexturedMesh& mesh) {
  for (size_t i = 0; i < mesh.textures.size(); ++i) {
    const std::string_view bytes = doc_->images[size_t(doc_->texture_image[i])];
    if (bytes.empty()) fail(fmt::format("images[{}]", doc_->texture_image[i]), "is empty");
    std::tie(mesh.textures[i].width, mesh.textures[i].height) =
        image_dimensions(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
  }
  if (options_.load_textures) mesh.textures = load_texture_pixels(mesh, options_.max_texture_pixels);
}

TexturedMesh GltfReader::read(ModelReadStats* stats) {
  std::string reason;
  std::string& data = doc_->storage.emplace_back();
  if (!read_whole_file(path_, data, reason)) fail_input("{}: {}", path_, reason);
  input_bytes_ = data.size();
  const GltfContainerParts parts = split_gltf_container(path_, data);
  try {
    doc_->json = json::parse(parts.json);
  } catch (const json::exception& e) {
    fail_input("{}: JSON: {}", path_, excerpt(e.what()));
  }
  if (!doc_->json.is_object()) fail("JSON", "the document is not an object");
  const json asset = doc_->json.value("asset", json::object());
  if (!asset.is_object() || !asset.contains("version") || !asset["version"].is_string() ||
      asset["version"].get<std::string>().rfind("2.", 0) != 0)
    fail("asset", "version is not 2.x (tightex reads glTF 2.0)");
  if (doc_->json.contains("extensionsRequired") && doc_->json["extensionsRequired"].is_array())
    for (const json& e : doc_->json["extensionsRequired"])
      if (!required_extension_understood(e)) fail("extensionsRequired", "{} is not supported", excerpt(e.dump()));
  if (doc_->json.contains("extensionsUsed") && doc_->json["extensionsUsed"].is_array())
    for (const json& e : doc_->json["extensionsUsed"]) quantized_ = quantized_ || e == "KHR_mesh_quantization";
  check_document_shape();
  load_buffers(parts.bin);
  check_buffer_views();
  load_images();
  ReadState state;
  const std::vector<MeshInstance> instances = scene_instances();
  const std::vector<size_t> meshes = meshes_of(instances);
  for (const size_t m : meshes) {
    const json& mesh = array("meshes")[m];
    if (!mesh.contains("primitives") || !mesh["primitives"].is_array()) fail(fmt::format("meshes[{}]", m), "primitives missing");
    for (size_t p = 0; p < mesh["primitives"].size(); ++p) read_primitive(m, p, state);
  }
  if (state.mesh.triangles.empty()) fail_input("{}: no triangle primitive is reached from the scene's nodes", path_);
  finish_normals(state);
  if (!state.any_colors) state.mesh.corner_color.clear();
  if (!state.any_tangents) state.mesh.corner_tangent.clear();
  if (!options_.flatten_scene) state.mesh.source_mesh_area_scale = area_scales(instances, array("meshes").size());
  TexturedMesh mesh = options_.flatten_scene ? flattened(state.mesh, instances) : std::move(state.mesh);
  mesh.source = path_;
  mesh.gltf = doc_;
  load_textures(mesh);
  if (stats != nullptr) {
    *stats = ModelReadStats{};
    stats->not_read = not_read_;
    stats->warnings = warnings_;
    if (options_.flatten_scene) stats->instances_flattened = instances.size();
  }
  return mesh;
}

}  // namespace

size_t gltf_component_size(int64_t component_type) {
  switch (component_type) {
    case 5120:
    case kUnsignedByte:
      return 1;
    case 5122:
    case kUnsignedShort:
      return 2;
    case kUnsignedInt:
    case kFloat:
      return 4;
    default:
      return 0;
  }
}

size_t gltf_type_components(const std::string& type) {
  static const std::map<std::string, size_t> kComponents{{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4},
                                                         {"MAT2", 4},   {"MAT3", 9}, {"MAT4", 16}};
  const auto it = kComponents.find(type);
  return it == kComponents.end() ? 0 : it->second;
}

const json* gltf_slot_holder(const json& m, const GltfSlot& slot) {
  if (!m.is_object()) return nullptr;
  const std::string_view holder = slot.holder;
  if (holder.empty()) return &m;
  const json* parent = &m;
  if (holder.rfind("KHR_", 0) == 0) {
    const auto e = m.find("extensions");
    if (e == m.end() || !e->is_object()) return nullptr;
    parent = &*e;
  }
  const auto h = parent->find(slot.holder);
  return h != parent->end() && h->is_object() ? &*h : nullptr;
}

json* gltf_slot_holder(json& m, const GltfSlot& slot) { return const_cast<json*>(gltf_slot_holder(std::as_const(m), slot)); }

bool gltf_extension_has_slots(const std::string& extension) {
  return std::any_of(std::begin(kGltfSlots), std::end(kGltfSlots), [&](const GltfSlot& s) { return extension == s.holder; });
}

GltfContainerParts split_gltf_container(const std::string& file, std::string_view data) {
  GltfContainerParts parts;
  if (data.size() < 4 || le32(data.data()) != kGlbMagic) {
    parts.json = data;
    return parts;
  }
  parts.binary = true;
  auto bad = [&](const std::string& problem) { fail_input("{}: GLB header: {}", file, problem); };
  if (data.size() < 20) bad(fmt::format("the file is {} bytes, shorter than a GLB header and its first chunk header (20)", data.size()));
  const uint32_t version = le32(data.data() + 4), length = le32(data.data() + 8);
  if (version != 2) bad(fmt::format("version {} is not 2", version));
  if (length > data.size() || length < 20) bad(fmt::format("length {} is not in 20..{} (the file's size)", length, data.size()));
  const uint32_t json_length = le32(data.data() + 12), json_type = le32(data.data() + 16);
  if (json_type != kChunkJson) bad(fmt::format("the first chunk is not JSON"));
  if (uint64_t(json_length) > uint64_t(length) - 20)
    bad(fmt::format("JSON chunk length {} runs past the GLB length {}", json_length, length));
  parts.json = data.substr(20, json_length);
  uint64_t at = 20 + uint64_t(json_length);
  at = (at + 3) & ~uint64_t(3);
  if (at + 8 <= length) {
    const uint32_t bin_length = le32(data.data() + at), bin_type = le32(data.data() + at + 4);
    if (bin_type == kChunkBin) {
      if (uint64_t(bin_length) > uint64_t(length) - at - 8)
        bad(fmt::format("BIN chunk length {} runs past the GLB length {}", bin_length, length));
      parts.bin = data.substr(size_t(at + 8), bin_length);
    }
  }
  return parts;
}

TexturedMesh read_gltf(const std::string& path, const ModelReadOptions& options, ModelReadStats* stats) {
  try {
    return GltfReader(path, options).read(stats);
  } catch (const json::exception& e) {
    // A member of another JSON type than glTF gives it (a string where a number belongs) that no check
    // above names more precisely.
    fail_input("{}: JSON: a value of the wrong type ({})", path, excerpt(e.what()));
  }
}

}  // namespace tightex
