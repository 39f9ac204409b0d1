// The textured triangle mesh as flat arrays (structure of arrays), as read from a model file and as
// written back. Texture coordinates and normals are per corner (3 per triangle), so a stage never has
// to reconcile split vertices: corner c of triangle t is index 3*t + c.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "tightex/image.hpp"
#include "tightex/vector.hpp"

namespace tightex {

using Tri = std::array<uint32_t, 3>;
constexpr uint32_t kNone = UINT32_MAX;

/// The texture maps a material may bind besides its base colour (Material::texture), each read through
/// the same texture coordinates. glTF: metallic-roughness (G roughness, B metallic), occlusion (R),
/// emissive, normal (tangent space), and the KHR_materials_* slots (specular colour and strength,
/// clearcoat, its roughness and normal, sheen colour and roughness, transmission, volume thickness,
/// iridescence and its thickness, anisotropy); OBJ: map_Ks (specular colour), map_Ke, map_Pr, map_Pm,
/// norm (tangent space), map_Bump / bump (a height map, baked as data), map_d, map_Ns and disp /
/// map_Disp.
enum class MaterialSlot : uint8_t {
  kMetallicRoughness,
  kOcclusion,
  kEmissive,
  kNormal,
  kSpecular,  // specular colour: OBJ map_Ks, KHR_materials_specular's specularColorTexture
  kRoughness,
  kMetallic,
  kBump,
  kSpecularStrength,  // KHR_materials_specular's specularTexture (A)
  kClearcoat,
  kClearcoatRoughness,
  kClearcoatNormal,
  kSheenColour,
  kSheenRoughness,
  kTransmission,
  kThickness,
  kIridescence,
  kIridescenceThickness,
  kAnisotropy,
  kOpacity,       // OBJ map_d
  kShininess,     // OBJ map_Ns
  kDisplacement,  // OBJ disp / map_Disp
};
constexpr size_t kMaterialSlots = 22;

/// How a map's texels are filtered: colour maps in linear light (sRGB decoded, filtered, re-encoded),
/// data maps as stored, tangent-space normal maps through the tangent frames (decoded to object space,
/// filtered there, encoded in the output's frame).
enum class SlotEncoding : uint8_t { kSrgbColour, kData, kTangentNormal };

/// Each slot's encoding, and its name in reports ("metallic_roughness", "occlusion", ...).
SlotEncoding slot_encoding(MaterialSlot slot);
const char* material_slot_name(MaterialSlot slot);
/// The channels a renderer reads from a slot's image: bit 0 red, 1 green, 2 blue, 3 alpha
/// (metallic-roughness green and blue, occlusion and the OBJ scalar maps red, specular strength and
/// sheen roughness alpha, colour and normal maps all three).
unsigned material_slot_channels(MaterialSlot slot);

/// Per channel (red, green, blue, alpha): what a viewer multiplies a slot's texels by, and shows alone
/// where the material binds no texture in the slot (docs/metrics.md, "effective values").
using SlotFactor = std::array<double, 4>;
/// Every slot's factor where the model says none: glTF's defaults (metallic and roughness 1, occlusion
/// strength 1, emissive 0, the KHR_materials_* layers off); OBJ's readers set their own.
std::array<SlotFactor, kMaterialSlots> default_slot_factors();
/// Every slot unbound (-1).
std::array<int, kMaterialSlots> unbound_slots();

/// One material: a name, a constant diffuse colour and optionally a diffuse texture image.
struct Material {
  std::string name;
  /// The base colour factor, linear as glTF's baseColorFactor; OBJ's Kd is read and written as the same
  /// number (as Blender and assimp convert between the two). An untextured face shows it as the texel
  /// linear_to_srgb(kd) would.
  std::array<double, 3> kd{1.0, 1.0, 1.0};
  int texture = -1;                           // index into TexturedMesh::textures, -1 = constant colour
  std::array<double, 2> uv_scale{1.0, 1.0};   // map_Kd -s
  std::array<double, 2> uv_offset{0.0, 0.0};  // map_Kd -o
  /// Per MaterialSlot: index into TexturedMesh::textures, -1 = not bound. A map is sampled at the same
  /// (transformed) texture coordinates as `texture`. One image bound to two slots is one texture.
  std::array<int, kMaterialSlots> maps = unbound_slots();
  /// Per MaterialSlot: its factor (glTF's metallic-roughness (1, roughnessFactor, metallicFactor, 1),
  /// occlusion strength, emissiveFactor times KHR_materials_emissive_strength, normal scale, the
  /// extensions' factors; OBJ's Ks, Ke, Pr, Pm, d, Ns where the slot has no map, 1 where it has one, as
  /// OBJ viewers show a map alone). Colour factors are linear, as glTF's.
  std::array<SlotFactor, kMaterialSlots> factor = default_slot_factors();
  /// Whether a viewer multiplies the base colour texture by kd (glTF's baseColorFactor does; OBJ
  /// viewers mostly show map_Kd alone).
  bool kd_multiplies_texture = false;
  /// OBJ: the material's MTL statements other than newmtl, Kd and the texture maps (Ka, Ks, Ke, Ns, Ni,
  /// d, Tr, illum, Pr, Pm, ...), as they came, which write_obj writes back.
  std::vector<std::string> mtl_statements;
};

/// A texture image and the path it came from (or will be written to).
struct Texture {
  std::string path;
  Image image;
  /// The size when the pixels are not loaded (yet): read from the file's header by a caller that
  /// decodes later. 0 when unknown. A loaded image's own size always wins (see texture_size).
  int width = 0, height = 0;
  /// Made from the model's vertex colours (texture_vertex_colours), not read from a file.
  bool from_vertex_colours = false;
  /// Where the model names it, for the message of a texture that cannot be loaded: "FILE:LINE: texture
  /// 'NAME' of material 'M'" (OBJ), "FILE:LINE: texture 'NAME' (comment TextureFile)" (PLY); empty for a
  /// glTF's (its document names it) and a texture made in memory.
  std::string named_at = {};
};

/// A glTF model's own document (scenes, nodes, materials, buffers), kept by read_gltf for write_gltf so
/// that what tightex does not change is written back as it came. Opaque: defined in src/io.
struct GltfDocument;

struct TexturedMesh {
  std::vector<Vec3> positions;      // per vertex
  std::vector<Tri> triangles;       // vertex indices, counter-clockwise = front
  std::vector<Vec2> corner_uv;      // 3 per triangle
  std::vector<Vec3> corner_normal;  // 3 per triangle, or empty when the model has none
  /// 3 per triangle, or empty: the tangent frame of a tangent-space normal map at each corner, as glTF's
  /// TANGENT: xyz the tangent (direction of increasing u), w = +1 or -1 the handedness, the bitangent
  /// (direction of increasing v) being w * cross(normal, tangent). Read from glTF's TANGENT, computed
  /// by compute_corner_tangents (core/tangents.hpp) otherwise.
  std::vector<Vec4> corner_tangent;
  /// 3 per triangle, or empty when the model has none: a vertex-coloured model's colours (red, green,
  /// blue, alpha), sRGB-encoded in [0, 1] as an 8-bit texture stores them.
  std::vector<std::array<float, 4>> corner_color;
  std::vector<int32_t> face_material;  // per triangle, index into materials (-1: none)
  std::vector<Material> materials;
  std::vector<Texture> textures;
  std::string source;  // file it was read from, for messages
  /// Per triangle, or empty (one source mesh): the mesh of the input file it belongs to (glTF: its mesh;
  /// a scene flattened to world space: its mesh instance). Vertices are welded within one source mesh,
  /// never across two, so two meshes with the same geometry stay two surfaces with texels of their own.
  /// Triangles of different source meshes share no vertex.
  std::vector<uint32_t> source_mesh;
  /// Per source mesh, or empty (1 each): how many times its own area the scene shows of it (glTF: the
  /// sum, over the nodes that show the mesh, of each node's area scale |det|^(2/3)). The texel budget
  /// and the surface PSNR weigh each mesh's area by it, as a viewer of the scene sees the surfaces.
  std::vector<double> source_mesh_area_scale;
  /// Per triangle of an output model: the input triangle it is (build_output_model fills it; empty in a
  /// model read from a file). write_gltf uses it to put each triangle back into its own glTF primitive.
  std::vector<uint32_t> input_triangle;
  /// The glTF document the model was read from (read_gltf), passed on to the output model; null for
  /// every other reader.
  std::shared_ptr<const GltfDocument> gltf;

  size_t num_vertices() const { return positions.size(); }
  size_t num_triangles() const { return triangles.size(); }
  /// Texture coordinate at a corner after the material's -s/-o transform (what a renderer samples).
  Vec2 sampled_uv(size_t triangle, int corner) const;
};

/// Width and height of texture i: its pixels' if loaded, else the header size recorded in the Texture.
std::pair<int, int> texture_size(const TexturedMesh& mesh, int i);

}  // namespace tightex
