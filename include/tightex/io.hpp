// Reading and writing models and texture images: Wavefront OBJ + MTL, PLY and glTF 2.0 (.gltf, .glb)
// with the textures they name; PNG and JPEG (and, for reading, WebP and what stb_image understands). Every reader refuses bad input with an
// InputError naming the file, the element and the problem.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "tightex/image.hpp"
#include "tightex/mesh.hpp"
#include "tightex/options.hpp"

namespace tightex {

/// The options of every model reader (read_obj, read_ply, read_gltf, read_model).
struct ModelReadOptions {
  bool load_textures = true;  // false: materials keep their texture path, no pixels
  size_t max_texture_pixels = size_t(1) << 30;
  /// glTF: every mesh instance in world space (node transforms applied, each node that shows a mesh
  /// its own copy, TexturedMesh::source_mesh its instance), as a format without a scene graph (OBJ,
  /// PLY) must hold it. Off: each mesh once, in its own space, for write_gltf to put back.
  bool flatten_scene = false;
  /// A file the model names (mtllib, map_*, TextureFile, a glTF buffer or image URI) may lie outside the
  /// folder of the file naming it: an absolute path, a `..` that leads out, a symbolic link out, a
  /// file: URI. Off (the default), such a reference is refused (InputError) where the file exists;
  /// one found inside the folder by a tail of its path (read_obj) is read.
  bool allow_outside_files = false;
};

/// What the reader did beyond plain reading, for the report.
struct ModelReadStats {
  size_t polygons_triangulated = 0;  // faces with more than 3 corners, fan-triangulated
  size_t lines = 0;                  // text lines read (a binary PLY: its header's)
  /// Files the MTL (a PLY: its TextureFile comments) names that were found only by ignoring case or by a tail of the path as written
  /// ("WRITTEN -> USED"), e.g. a Windows exporter's absolute path.
  std::vector<std::string> paths_found;
  size_t vertex_coloured_triangles = 0;  // triangles textured from their vertex colours (read_model)
  /// What the model holds that the reader left as it was, one entry each (a glTF points or lines
  /// primitive, "meshes[0].primitives[1] (points)"): write_gltf writes it back as it came, the other
  /// writers cannot.
  std::vector<std::string> not_read;
  /// What the reader read otherwise than the file asks, one line each (a KTX2 texture read from its
  /// fallback image); the command prints them as warnings.
  std::vector<std::string> warnings;
  size_t instances_flattened = 0;  // glTF read with flatten_scene: the mesh instances placed in world space
};

/// Reads an OBJ file and its MTL libraries and textures.
/// Requires: a readable OBJ file with at least one triangle and texture coordinates on every face.
/// Guarantees: positions finite; triangle indices in range; corner_uv finite and 3 per triangle;
/// face_material in range or -1; every material with map_Kd has a loaded texture.
/// Throws InputError with "FILE:LINE: problem" for any malformed or unsupported content.
TexturedMesh read_obj(const std::string& path, const ModelReadOptions& options = {}, ModelReadStats* stats = nullptr);

/// Reads a PLY file (ascii, binary_little_endian or binary_big_endian) as photogrammetry tools write
/// it, with the textures its `comment TextureFile <name>` lines name (relative to the PLY's folder,
/// found as read_obj finds an MTL's files). Elements may come in any order; elements and properties
/// other than those below are skipped. Vertex: x y z, and texture coordinates as s t, u v or
/// texture_u texture_v. Face: a vertex_indices (or vertex_index) list, fan-triangulated beyond three
/// corners; a texcoord list (two values a corner), which wins over the vertex's; texnumber, the
/// texture of the face (-1: none; without it every face has the first). One material per TextureFile.
/// Requires: a readable PLY with at least one face, and texture coordinates for every face.
/// Guarantees: those of read_obj; no allocation before the header's counts are checked against the
/// file's size.
/// Throws InputError on one line, "FILE:LINE: problem" for the header and for an ascii body,
/// "FILE: ELEMENT N: problem" for a binary body, for any malformed, lying or unsupported content.
TexturedMesh read_ply(const std::string& path, const ModelReadOptions& options = {}, ModelReadStats* stats = nullptr);

/// Gives every triangle that has corner colours (TexturedMesh::corner_color) but no texture (and whose
/// material binds no other map, which reads the triangle's own coordinates) a texture holding those
/// colours: per material a copy reading it (its name and scalars kept; "vertex_colours" for triangles
/// without a material) and one new texture (its path the model's
/// own with "_colours.png", never read), in which each such triangle has a cell of 2 x 2 texels, its
/// corners at three texel centres and the fourth texel the colours' linear extrapolation, so that
/// bilinear sampling anywhere inside the triangle gives the colours' linear interpolation (to 8 bits;
/// exactly, except where the extrapolated texel leaves [0, 1]). The material's Kd, if it had one,
/// multiplies the colours. Every later stage then treats the colours as any input texture; the default
/// budget gives such a triangle kTexelsPerColouredTriangle texels (default_texels, tightex.hpp).
/// Requires: corner_color empty or 3 per triangle. Returns the number of triangles that took their
/// colours. Throws InputError when the texture would exceed `max_pixels`.
size_t texture_vertex_colours(TexturedMesh& mesh, size_t max_pixels = size_t(1) << 30);

/// Reads a glTF 2.0 model: a .glb, or a .gltf with its buffers and images in files beside it (found as
/// read_obj finds an MTL's files) or in base64 data URIs. Every triangle primitive (mode 4, 5 or 6,
/// indexed or not) of every mesh the scene reaches (the default scene, else scene 0, else every root
/// node) is read, each mesh once and in its own local space (source_mesh: the glTF mesh; a mesh that
/// two nodes use is one set of triangles, source_mesh_area_scale the area its nodes show of it), or
/// with options.flatten_scene every instance in world space (ModelReadOptions::flatten_scene).
/// Read: POSITION (exactly as stored), NORMAL, the TEXCOORD_n its material's baseColorTexture uses
/// (with KHR_texture_transform's offset, rotation and scale applied: the corner UVs are what a
/// renderer samples), COLOR_0 (into corner_color, converted from linear to sRGB), the base colour
/// texture (PNG, JPEG, WebP; one Texture per glTF image; a KTX2 or DDS texture from its fallback
/// source, stats->warnings saying so) and baseColorFactor (Material::kd).
/// A sampler other than REPEAT is accepted while the texture coordinates stay in [0,1]. Points and
/// lines primitives are left as they are (stats->not_read). The document itself is kept in
/// TexturedMesh::gltf for write_gltf.
/// Requires: a readable glTF 2.0 file with at least one triangle primitive reached from its scene.
/// Guarantees: those of read_obj (texture coordinates of an untextured primitive without TEXCOORD_0 are
/// 0); every index, offset, count and stride checked against the document and the buffers' real sizes
/// before any byte is read; no allocation sized by a count before it is checked against a buffer.
/// Throws InputError "FILE: ELEMENT: problem" (the element as the JSON names it, "accessors[3]",
/// "GLB header") for malformed, lying or unsupported content: sparse accessors, skins, morph targets,
/// Draco or meshopt compression, a texture whose UV set the primitive lacks, a KTX2 or DDS texture
/// without fallback.
TexturedMesh read_gltf(const std::string& path, const ModelReadOptions& options = {}, ModelReadStats* stats = nullptr);

/// The textures of `mesh`, read with load_textures false, with their pixels: each decoded from its file,
/// or a glTF's from the document the model keeps (TexturedMesh::gltf); a texture that has its pixels (one
/// made from vertex colours) as it is. Reads `mesh` only, so that one thread decodes while another works
/// on the geometry; the model is not parsed again. Throws the InputError the reader would have thrown
/// with load_textures true for the first texture, in order, that cannot be loaded.
std::vector<Texture> load_texture_pixels(const TexturedMesh& mesh, size_t max_pixels = size_t(1) << 30);

/// Reads a model by its file name's extension, without case: .ply with read_ply, .gltf and .glb with
/// read_gltf, anything else with read_obj; then texture_vertex_colours. Requires, guarantees and throws
/// as they do; a 3D Tiles payload (.b3dm, .i3dm, .pnts, .cmpt) is refused with an InputError naming the
/// tile runner.
TexturedMesh read_model(const std::string& path, const ModelReadOptions& options = {}, ModelReadStats* stats = nullptr);

/// ImageEncoding::png_level's fast setting: zlib level 1, the Z_RLE strategy and the UP filter on every
/// row: several times faster than level 6, files about a tenth larger (BENCHMARKS.md, "Options").
constexpr int kPngLevelFast = -1;
/// ImageEncoding::png_level's default: zlib's and libpng's own default level, with the adaptive row
/// filter, so that re-saving with the usual tools gives no smaller file.
constexpr int kDefaultPngLevel = 6;
constexpr int kDefaultJpegQuality = 92;
constexpr int kDefaultWebpQuality = 90;

/// How the texture images of a model are encoded: the format and its setting. An ImageFormat converts
/// to it with the defaults, so a writer call that names only a format means the fast PNG or quality 92.
struct ImageEncoding {
  ImageFormat format = ImageFormat::kPng;
  /// PNG: kPngLevelFast, or 0..9: that zlib level with zlib's default strategy and the adaptive choice
  /// of filter per row (9: the smallest file, the slowest).
  int png_level = kDefaultPngLevel;
  int jpeg_quality = kDefaultJpegQuality;  // JPEG: 1..100
  int webp_quality = kDefaultWebpQuality;  // WebP: 1..100 (lossy)
  bool webp_lossless = false;              // WebP: lossless instead
  /// Per texture of the model written, its codec (empty: every texture as `format`), for an output
  /// whose images keep their input's codecs: a PNG normal map beside a JPEG base colour stays PNG.
  std::vector<ImageFormat> formats;

  ImageEncoding() = default;
  ImageEncoding(ImageFormat image_format) : format(image_format) {}  // NOLINT(google-explicit-constructor): see above
  ImageEncoding(ImageFormat image_format, int png, int jpeg) : format(image_format), png_level(png), jpeg_quality(jpeg) {}
  /// Whether a written image may differ from its pixels (JPEG, lossy WebP), for any texture.
  bool lossy() const;
  /// The encoding of texture i: this one, with formats[i] where given.
  ImageEncoding of_texture(size_t i) const;
};

/// The image encoded as `encoding` says, in memory: the bytes save_image writes. Throws as save_image
/// does (InputError for a setting out of range, naming `name`).
std::string encode_image(const Image& image, const ImageEncoding& encoding, const std::string& name = "image");

/// The file extension of a format, with its dot: ".png", ".jpg", ".webp".
const char* image_extension(ImageFormat format);

/// Loads an image file. Throws InputError naming the file and the problem (missing, unreadable,
/// truncated, corrupt, unsupported, or larger than max_pixels) -- never crashes on a bad file.
Image load_image(const std::string& path, size_t max_pixels = size_t(1) << 30);

/// Writes an image (RGB; alpha is dropped when it is 255 everywhere) as `encoding` says. The default
/// PNG settings are fast ones (tightex writes 8K textures; zlib level 9 would dominate the run time).
/// Requires: a non-empty image. Throws InputError naming the file when it cannot be written, or when
/// encoding.png_level is not kPngLevelFast or 0..9, or encoding.jpeg_quality is not 1..100 (for its format).
void save_image(const std::string& path, const Image& image, const ImageEncoding& encoding);

/// save_image in `format` with the default PNG settings, or JPEG at `jpeg_quality` (1..100).
void save_image(const std::string& path, const Image& image, ImageFormat format, int jpeg_quality = kDefaultJpegQuality);

/// Writes OUTDIR/<name>.obj, <name>.mtl and every texture of `mesh` (Texture::path is the file stem inside
/// OUTDIR; .png or .jpg is appended), each image encoded as `encoding` says (save_image). Every file is first written under a temporary
/// name and renamed only once all are complete (the OBJ last), so a failed run leaves no model behind. Positions are written in shortest
/// round-trip form, so they read back bit-identical; texture coordinates likewise, so no UV triangle collapses on the way to the file.
/// Throws InputError naming the path on failure (and for an encoding save_image refuses, before any file is written). Returns one sentence
/// per map slot the MTL cannot bind (glTF's occlusion; a metallic-roughness image beside a separate roughness or metallic map), for a
/// warning; the images are written all the same.
std::vector<std::string> write_obj(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                   const ImageEncoding& encoding);

/// Writes OUTDIR/<name>.ply and every texture of `mesh` (named and encoded as write_obj does), atomically as
/// write_obj does (the PLY last): a binary_little_endian PLY as photogrammetry tools write it and
/// MeshLab reads it. Header: one `comment TextureFile <file>` per texture, in the order of
/// mesh.textures, so that a face's `texnumber` indexes them. Vertex: x y z, as float when every
/// coordinate is exactly a float, else as double, so positions always read back bit-identical; no
/// normals (TexturedMesh's are per corner, and the model's own shading is recomputed by viewers).
/// Face: `vertex_indices` (uchar count, int indices), `texcoord` (uchar 6, float: the coordinate the
/// renderer samples, TexturedMesh::sampled_uv, since PLY has no texture transform; float keeps it
/// within 2^-24 relative, far below a texel of any texture tightex writes) and `texnumber` (int: the
/// texture of the face's material; -1 where the face has no material or its material has no texture).
/// PLY has no place for a material's name or Kd colour: they are not written; nor for its other maps
/// (Material::maps): their images are written beside the model (and named by TextureFile comments, as
/// every texture is) but bound to no face. Returns one sentence per such map slot, for a warning.
/// Requires: a mesh as read_model guarantees it, with fewer than 2^31 vertices.
/// Throws InputError naming the path on failure (too many vertices, cannot create, write or rename).
std::vector<std::string> write_ply(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                   const ImageEncoding& encoding);

/// The two containers of glTF: JSON text with a .bin buffer and image files beside it, or one .glb.
enum class GltfContainer { kGltf, kGlb };

/// Writes OUTDIR/<name>.glb, or <name>.gltf with <name>.bin and the texture files (named
/// and encoded as write_obj does), atomically as write_obj does (the model last). For a model read by read_gltf
/// (mesh.gltf set, mesh.input_triangle naming each triangle's input triangle) the input's document is
/// written back: scenes, nodes (transforms as they were), meshes' names, extras, materials' factors,
/// alphaMode, alphaCutoff, doubleSided, extensions that do not refer to textures, points and lines
/// primitives and what only they use; each triangle goes back to its own primitive, which gets new
/// accessors (POSITION bit-identical, NORMAL where it had one, TEXCOORD_0, indices; vertices split at
/// the new seams; one primitive per new texture it spans) and a copy of its material whose
/// baseColorTexture is the new texture on TEXCOORD_0 (an untextured material gets the texture and a
/// white base colour factor). The material's other texture slots (normal, occlusion,
/// metallicRoughness, emissive, textures of material extensions) cannot follow the new texture
/// coordinates and are removed; so are TANGENT, COLOR_n and other TEXCOORD_n of the triangles and the
/// extensions of their primitives (KHR_materials_variants: the variants name the old materials), and
/// every buffer view, accessor, image and texture nothing uses any more. Any other model gets a fresh
/// document: one node, one mesh, one primitive per material.
/// Returns one line per kind of thing removed ("materials[0].normalTexture", ...), for a warning.
/// Requires: a mesh as the pipeline's output guarantees it, fewer than 2^32 vertices per primitive.
/// Throws InputError naming the path on failure.
std::vector<std::string> write_gltf(const TexturedMesh& mesh, const std::string& outdir, const std::string& name,
                                    const ImageEncoding& encoding, GltfContainer container);

}  // namespace tightex
