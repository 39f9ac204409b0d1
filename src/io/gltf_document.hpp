// The glTF document read_gltf keeps for write_gltf (TexturedMesh::gltf), and the parts of glTF both use:
// the container (GLB or JSON text) and the checked view of an accessor's bytes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "tightex/mesh.hpp"

namespace tightex {

/// A vertex attribute that tightex does not change (an application's `_BATCHID` or `_FEATURE_ID_0`, a
/// second UV set, COLOR_0 beside a texture): write_gltf copies each output vertex's element from the
/// input vertex it is. Checked by read_gltf: one element per position, all inside its buffer.
struct GltfVertexAttribute {
  std::string name;
  const unsigned char* data = nullptr;  // element i at data + i * stride; nullptr: all zeros (no bufferView)
  size_t stride = 0, element_size = 0;
  int64_t component_type = 0;
  std::string type;  // "SCALAR", "VEC2", ...
  bool normalized = false;
};

/// A triangle primitive that read_gltf read (mode 4, 5 or 6): where it is in the document.
struct GltfPrimitive {
  size_t mesh = 0, primitive = 0;
  int material = -1;                         // the glTF material, -1: the default material
  bool normals = false;                      // it has NORMAL (written back only then)
  std::vector<GltfVertexAttribute> carried;  // attributes written back unchanged, per vertex
};

struct GltfDocument {
  nlohmann::json json;  // the document as read
  /// The bytes read: the model file, each file a URI names (once, however many URIs name it), each
  /// data URI decoded. The views below point into them.
  std::deque<std::string> storage;
  std::vector<std::string_view> buffers;     // each buffer's bytes, exactly byteLength of them
  std::vector<std::string_view> images;      // each image's encoded bytes (file, data URI or bufferView)
  std::vector<GltfPrimitive> primitives;     // the triangle primitives read, in reading order
  std::vector<uint32_t> triangle_primitive;  // per triangle of the model read: index into primitives
  std::vector<uint32_t> vertex_source;       // per vertex of the model read: its index in its primitive's accessors
  /// Per texture of the model read: the glTF image it is.
  std::vector<int> texture_image;
  /// Read with ModelReadOptions::flatten_scene: the model holds the scene's instances in world space,
  /// which write_gltf does not put back into this document (it writes a fresh one).
  bool flattened = false;
};

/// Where a MaterialSlot's texture info sits in a glTF material: `holder` is "" (the material itself),
/// "pbrMetallicRoughness", or a KHR_materials_* extension (under "extensions"); `key` the texture
/// info's name there. read_gltf reads these slots and write_gltf binds them again.
struct GltfSlot {
  MaterialSlot slot;
  const char* holder;
  const char* key;
};
inline constexpr GltfSlot kGltfSlots[] = {
    {MaterialSlot::kMetallicRoughness, "pbrMetallicRoughness", "metallicRoughnessTexture"},
    {MaterialSlot::kOcclusion, "", "occlusionTexture"},
    {MaterialSlot::kEmissive, "", "emissiveTexture"},
    {MaterialSlot::kNormal, "", "normalTexture"},
    {MaterialSlot::kSpecularStrength, "KHR_materials_specular", "specularTexture"},
    {MaterialSlot::kSpecular, "KHR_materials_specular", "specularColorTexture"},
    {MaterialSlot::kClearcoat, "KHR_materials_clearcoat", "clearcoatTexture"},
    {MaterialSlot::kClearcoatRoughness, "KHR_materials_clearcoat", "clearcoatRoughnessTexture"},
    {MaterialSlot::kClearcoatNormal, "KHR_materials_clearcoat", "clearcoatNormalTexture"},
    {MaterialSlot::kSheenColour, "KHR_materials_sheen", "sheenColorTexture"},
    {MaterialSlot::kSheenRoughness, "KHR_materials_sheen", "sheenRoughnessTexture"},
    {MaterialSlot::kTransmission, "KHR_materials_transmission", "transmissionTexture"},
    {MaterialSlot::kThickness, "KHR_materials_volume", "thicknessTexture"},
    {MaterialSlot::kIridescence, "KHR_materials_iridescence", "iridescenceTexture"},
    {MaterialSlot::kIridescenceThickness, "KHR_materials_iridescence", "iridescenceThicknessTexture"},
    {MaterialSlot::kAnisotropy, "KHR_materials_anisotropy", "anisotropyTexture"},
};

/// The object of material `m` that holds `slot`'s texture info (GltfSlot::holder), or null when the
/// material has none.
const nlohmann::json* gltf_slot_holder(const nlohmann::json& m, const GltfSlot& slot);
nlohmann::json* gltf_slot_holder(nlohmann::json& m, const GltfSlot& slot);

/// Whether `extension` is one whose texture slots kGltfSlots lists (its textures follow the new
/// texture coordinates).
bool gltf_extension_has_slots(const std::string& extension);

/// The JSON text and the BIN chunk of a .glb, or the whole text of a .gltf.
struct GltfContainerParts {
  std::string_view json;
  std::string_view bin;  // empty when there is none
  bool binary = false;
};

/// Splits `data` (a whole .glb or .gltf file) into its JSON and BIN. Throws InputError "FILE: GLB
/// header: problem" for a GLB whose header or chunk lengths lie.
GltfContainerParts split_gltf_container(const std::string& file, std::string_view data);

/// The sizes of glTF's component types (5120..5126), 0 for any other value.
size_t gltf_component_size(int64_t component_type);

/// The number of components of an accessor type ("SCALAR" 1 ... "MAT4" 16), 0 for any other.
size_t gltf_type_components(const std::string& type);

}  // namespace tightex
