// Tests for glTF in and out: read_gltf on a hand-built GLB (and the same as .gltf with a .bin file or
// a data URI), what it refuses (a catalogue of lying documents, each one line naming the file and the
// element), write_gltf read back (positions bit for bit, the document's nodes, materials and points
// kept), the command line on the Khronos models and on an OBJ scan converted to GLB here, and every
// written file through the Khronos glTF-Validator and three.js's GLTFLoader (tests/gltf, when node is
// installed).
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <string>

#include "command_line.hpp"
#include "core/error.hpp"
#include "gltf_builder.hpp"
#include "gltf_checks.hpp"
#include "io/gltf_document.hpp"
#include "mesh_catalogue.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"
#include "tightex/tightex.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::GridGltf;

fs::path scratch(const std::string& name) { return testing::scratch_folder("gltf_" + name); }
void write_file(const fs::path& p, const std::string& bytes) { testing::write_whole(p, bytes); }
std::string read_file(const fs::path& p) { return testing::read_whole(p); }
double linear_to_srgb(double c) { return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055; }

/// The grid written as a GLB into `dir`.
fs::path grid_glb(const fs::path& dir, const GridGltf& g = testing::grid_gltf()) {
  const fs::path p = dir / "grid.glb";
  write_file(p, testing::make_glb(g.doc, g.bin));
  return p;
}

TEST(GltfReader, ReadsTheHandBuiltGlbOnceInLocalSpace) {
  const fs::path dir = scratch("read");
  const GridGltf g = testing::grid_gltf();
  ModelReadStats stats;
  const TexturedMesh m = read_gltf(grid_glb(dir, g).string(), {}, &stats);
  // Two nodes use the mesh: its triangles are read once, untransformed.
  ASSERT_EQ(m.num_triangles(), g.triangles);
  ASSERT_EQ(m.num_vertices(), 25u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(m.positions[size_t(i)].x(), double(float(i / 3.0f + 0.1f)));
  EXPECT_EQ(m.positions[5].y(), double(float(1 / 7.0f)));
  // Corner UVs in tightex's convention (v up): 1 - the glTF v.
  EXPECT_FLOAT_EQ(float(m.corner_uv[0].x()), 0.1f);
  EXPECT_FLOAT_EQ(float(m.corner_uv[0].y()), 1.0f - 0.1f);
  ASSERT_EQ(m.corner_normal.size(), 3 * m.num_triangles());
  EXPECT_EQ(m.corner_normal[0], Vec3(0, 0, 1));
  EXPECT_TRUE(m.corner_color.empty());
  ASSERT_EQ(m.materials.size(), 1u);
  EXPECT_EQ(m.materials[0].name, "grid material");
  EXPECT_EQ(m.materials[0].kd[0], 0.5);  // the linear factor, as OBJ's Kd holds it
  ASSERT_EQ(m.textures.size(), 2u);      // the base colour, then the normal map (another slot)
  EXPECT_EQ(m.textures[0].image.width, 16);
  EXPECT_EQ(m.materials[0].texture, 0);
  EXPECT_EQ(m.materials[0].maps[size_t(MaterialSlot::kNormal)], 1);
  ASSERT_EQ(stats.not_read.size(), 1u);
  EXPECT_NE(stats.not_read[0].find("meshes[0].primitives[1] (points)"), std::string::npos);
  ASSERT_NE(m.gltf, nullptr);
}

TEST(GltfReader, ReadsGltfWithABinFileOrADataUriAsTheGlb) {
  const fs::path dir = scratch("text");
  GridGltf g = testing::grid_gltf();
  const TexturedMesh glb = read_gltf(grid_glb(dir, g).string());
  g.doc["buffers"][0]["uri"] = "grid data.bin";
  write_file(dir / "grid data.bin", g.bin);
  write_file(dir / "file.gltf", g.doc.dump());
  static const char* kBase64 = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string b64;
  for (size_t i = 0; i < g.bin.size(); i += 3) {
    uint32_t n = uint32_t(uint8_t(g.bin[i])) << 16;
    if (i + 1 < g.bin.size()) n |= uint32_t(uint8_t(g.bin[i + 1])) << 8;
    if (i + 2 < g.bin.size()) n |= uint8_t(g.bin[i + 2]);
    b64 += kBase64[(n >> 18) & 63], b64 += kBase64[(n >> 12) & 63];
    b64 += i + 1 < g.bin.size() ? kBase64[(n >> 6) & 63] : '=';
    b64 += i + 2 < g.bin.size() ? kBase64[n & 63] : '=';
  }
  g.doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + b64;
  write_file(dir / "uri.gltf", g.doc.dump());
  for (const char* name : {"file.gltf", "uri.gltf"}) {
    const TexturedMesh m = read_gltf((dir / name).string());
    EXPECT_EQ(m.positions, glb.positions) << name;
    EXPECT_EQ(m.triangles, glb.triangles) << name;
    EXPECT_EQ(m.corner_uv, glb.corner_uv) << name;
    EXPECT_EQ(m.textures[0].image.pixels, glb.textures[0].image.pixels) << name;
  }
}

// A model read without pixels keeps its document, from which load_texture_pixels decodes the images
// later (as the CLI does beside the geometric stages): the pixels a read with them gives, and for an
// image that does not decode the error that read gives.
TEST(GltfReader, ImagesDecodedAfterTheReadAreThoseTheReadGives) {
  const fs::path dir = scratch("later");
  const fs::path glb = grid_glb(dir);
  ModelReadOptions geometry_only;
  geometry_only.load_textures = false;
  const TexturedMesh geometry = read_gltf(glb.string(), geometry_only);
  const TexturedMesh full = read_gltf(glb.string());
  ASSERT_EQ(geometry.textures.size(), 2u);
  EXPECT_TRUE(geometry.textures[0].image.empty());
  const std::vector<Texture> decoded = load_texture_pixels(geometry);
  ASSERT_EQ(decoded.size(), 2u);
  for (size_t i = 0; i < 2; ++i) EXPECT_EQ(decoded[i].image.pixels, full.textures[i].image.pixels) << i;
  // An image whose header is whole and whose data is cut short: sized at the read, refused at the decode.
  GridGltf g = testing::grid_gltf();
  save_image((dir / "whole.png").string(), Image(16, 16, Rgba8{9, 8, 7, 255}), ImageFormat::kPng);
  write_file(dir / "cut.png", read_file(dir / "whole.png").substr(0, 40));
  g.doc["images"][0] = {{"uri", "cut.png"}};
  const fs::path cut = grid_glb(dir, g);
  std::string message;
  try {
    read_gltf(cut.string());
  } catch (const InputError& e) {
    message = e.what();
  }
  EXPECT_EQ(message.rfind(cut.string() + ": images[0]", 0), 0u) << message;
  const TexturedMesh cut_geometry = read_gltf(cut.string(), geometry_only);
  try {
    load_texture_pixels(cut_geometry);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST(GltfReader, AppliesTextureTransformWithItsRotation) {
  const fs::path dir = scratch("transform");
  GridGltf g = testing::grid_gltf();
  json& info = g.doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"];
  info["extensions"]["KHR_texture_transform"] = {{"offset", {0.25, 0.0}}, {"scale", {0.5, 2.0}}};
  const TexturedMesh m = read_gltf(grid_glb(dir, g).string());
  EXPECT_NEAR(m.corner_uv[0].x(), 0.25 + 0.5 * double(0.1f), 1e-12);
  EXPECT_NEAR(m.corner_uv[0].y(), 1.0 - 2.0 * double(0.1f), 1e-12);
  // A quarter turn takes u to -v and v to u (glTF's v down): the point (0.1, 0.1) scaled to (0.05, 0.2)
  // lands on offset + (0.2, -0.05), as TextureTransformTest's "correct" marker asks.
  info["extensions"]["KHR_texture_transform"]["rotation"] = std::numbers::pi / 2;
  const TexturedMesh turned = read_gltf(grid_glb(dir, g).string());
  EXPECT_NEAR(turned.corner_uv[0].x(), 0.25 + 2.0 * double(0.1f), 1e-12);
  EXPECT_NEAR(turned.corner_uv[0].y(), 1.0 - (0.0 - 0.5 * double(0.1f)), 1e-12);
  info["extensions"]["KHR_texture_transform"]["rotation"] = "half";
  try {
    read_gltf(grid_glb(dir, g).string());
    ADD_FAILURE() << "a rotation that is not a number was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rotation"), std::string::npos) << e.what();
  }
}

TEST(GltfReader, ReadsStripsAndFansWithTheirWinding) {
  const fs::path dir = scratch("strip");
  GridGltf g = testing::grid_gltf();
  json& p = g.doc["meshes"][0]["primitives"][0];
  p.erase("indices");
  p["mode"] = 5;  // strip over the first 25 vertices: 23 triangles
  const TexturedMesh strip = read_gltf(grid_glb(dir, g).string());
  ASSERT_EQ(strip.num_triangles(), 23u);
  EXPECT_EQ(strip.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(strip.triangles[1], (Tri{2, 1, 3}));
  p["mode"] = 6;
  const TexturedMesh fan = read_gltf(grid_glb(dir, g).string());
  ASSERT_EQ(fan.num_triangles(), 23u);
  EXPECT_EQ(fan.triangles[0], (Tri{1, 2, 0}));
}

/// Appends to the grid (of 25 vertices) a normalized unsigned byte VEC4 accessor, each vertex i's colour
/// (r, g, i, a); returns its index.
size_t add_colour_accessor(GridGltf& g, uint8_t r, uint8_t gr, uint8_t a) {
  std::string colours;
  for (int i = 0; i < 25; ++i)
    for (const uint8_t c : {r, gr, uint8_t(i), a}) colours.push_back(char(c));
  while (g.bin.size() % 4 != 0) g.bin.push_back('\0');
  g.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", g.bin.size()}, {"byteLength", colours.size()}});
  g.bin += colours;
  g.doc["buffers"][0]["byteLength"] = g.bin.size();
  g.doc["accessors"].push_back(
      {{"bufferView", g.doc["bufferViews"].size() - 1}, {"componentType", 5121}, {"normalized", true}, {"count", 25}, {"type", "VEC4"}});
  return g.doc["accessors"].size() - 1;
}

TEST(GltfReader, ReadsVertexColoursAsSrgb) {
  const fs::path dir = scratch("colour");
  GridGltf g = testing::grid_gltf();
  g.doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = add_colour_accessor(g, 0, 255, 128);
  const TexturedMesh m = read_gltf(grid_glb(dir, g).string());
  ASSERT_EQ(m.corner_color.size(), 3 * m.num_triangles());
  const uint32_t v = m.triangles[0][0];
  EXPECT_EQ(m.corner_color[0][0], 0.0f);
  EXPECT_EQ(m.corner_color[0][1], 1.0f);
  EXPECT_NEAR(m.corner_color[0][2], linear_to_srgb(v / 255.0), 1e-6);
  EXPECT_NEAR(m.corner_color[0][3], 128 / 255.0, 1e-6);  // alpha is not a colour
}

// Per-corner colours (and normals) of a primitive beside one without them: the corners of the one
// without get the defaults (white; the face's normal) in either order, and an attribute no primitive
// has (TANGENT here) stays empty.
TEST(GltfReader, CornersOfAPrimitiveWithoutAnAttributeGetItsDefault) {
  for (const bool colour_first : {true, false}) {
    const fs::path dir = scratch(colour_first ? "partial_colour_first" : "partial_colour_second");
    GridGltf g = testing::grid_gltf();
    const size_t colour = add_colour_accessor(g, 10, 20, 255);
    auto& primitives = g.doc["meshes"][0]["primitives"];
    nlohmann::json plain = primitives[0];
    plain["attributes"].erase("NORMAL");
    nlohmann::json coloured = primitives[0];
    coloured["attributes"]["COLOR_0"] = colour;
    primitives[0] = colour_first ? coloured : plain;
    primitives.push_back(colour_first ? plain : coloured);
    const TexturedMesh m = read_gltf(grid_glb(dir, g).string());
    ASSERT_EQ(m.num_triangles(), 2 * g.triangles);
    ASSERT_EQ(m.corner_color.size(), 3 * m.num_triangles());
    ASSERT_EQ(m.corner_normal.size(), 3 * m.num_triangles());
    EXPECT_TRUE(m.corner_tangent.empty());
    const size_t first_coloured = colour_first ? 0 : g.triangles;
    const size_t first_white = colour_first ? g.triangles : 0;
    for (size_t t = first_white; t < first_white + g.triangles; ++t)
      for (size_t k = 0; k < 3; ++k) EXPECT_EQ(m.corner_color[3 * t + k], (std::array<float, 4>{1, 1, 1, 1})) << "triangle " << t;
    for (size_t t = first_coloured; t < first_coloured + g.triangles; ++t) {
      EXPECT_NEAR(m.corner_color[3 * t][0], linear_to_srgb(10 / 255.0), 1e-6);
      EXPECT_NEAR(m.corner_color[3 * t][3], 1.0, 1e-6);
    }
    for (const Vec3& n : m.corner_normal) EXPECT_NEAR(std::abs(n.z()), 1.0, 1e-6);  // NORMAL or the flat grid's face normal
  }
}

/// One lying document: a change to the grid, and a word the message must hold.
struct Lie {
  const char* name;
  std::function<void(GridGltf&)> change;
  const char* element;
};

void set_u32(std::string& bytes, size_t at, uint32_t v) { std::memcpy(&bytes[at], &v, 4); }

std::vector<Lie> lies() {
  return {
      {"count beyond the view", [](GridGltf& g) { g.doc["accessors"][0]["count"] = 1000000000; }, "accessors[0]"},
      {"view beyond the buffer", [](GridGltf& g) { g.doc["bufferViews"][1]["byteOffset"] = 1u << 30; }, "bufferViews[1]"},
      {"stride below the element", [](GridGltf& g) { g.doc["bufferViews"][0]["byteStride"] = 4; }, "bufferViews[0]"},
      {"component type", [](GridGltf& g) { g.doc["accessors"][0]["componentType"] = 5124; }, "accessors[0]"},
      {"accessor type", [](GridGltf& g) { g.doc["accessors"][0]["type"] = "VEC7"; }, "accessors[0]"},
      {"position not float", [](GridGltf& g) { g.doc["accessors"][0]["componentType"] = 5121; }, "POSITION"},
      {"accessor index", [](GridGltf& g) { g.doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 99; }, "accessors[99]"},
      {"index out of range", [](GridGltf& g) { set_u32(g.bin, size_t(g.doc["bufferViews"][3]["byteOffset"]), 999); }, "out of range"},
      {"non-finite position", [](GridGltf& g) { set_u32(g.bin, 0, 0x7fc00000u); }, "POSITION entry 0"},
      {"missing image",
       [](GridGltf& g) {
         g.doc["images"][0] = {{"uri", "missing.png"}};
       },
       "images[0]"},
      {"undecodable data URI",
       [](GridGltf& g) {
         g.doc["images"][1] = {{"uri", "data:image/png;base64,@@@@"}};
       },
       "images[1]"},
      {"corrupt image",
       [](GridGltf& g) {
         g.doc["images"][0] = {{"uri", "data:image/png;base64,iVBORw0KGgoAAAA="}};
       },
       "images[0]"},
      {"buffer longer than BIN", [](GridGltf& g) { g.doc["buffers"][0]["byteLength"] = g.bin.size() + 100; }, "buffers[0]"},
      {"sparse accessor",
       [](GridGltf& g) {
         g.doc["accessors"][0]["sparse"] = {{"count", 1}};
       },
       "sparse"},
      {"skinned", [](GridGltf& g) { g.doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = 0; }, "JOINTS_0"},
      {"morph targets",
       [](GridGltf& g) {
         g.doc["meshes"][0]["primitives"][0]["targets"] = {{{"POSITION", 0}}};
       },
       "morph"},
      {"draco", [](GridGltf& g) { g.doc["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"] = json::object(); },
       "draco"},
      {"missing UV set", [](GridGltf& g) { g.doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = 1; },
       "TEXCOORD_1"},
      {"carried attribute too short",
       [](GridGltf& g) {
         g.doc["meshes"][0]["primitives"][0]["attributes"]["_BATCHID"] = 4;  // the points' 3 positions
       },
       "_BATCHID has 3 elements"},
      {"carried attribute beyond its view",
       [](GridGltf& g) {
         g.doc["accessors"].push_back({{"bufferView", 2}, {"componentType", 5126}, {"count", 25}, {"type", "MAT4"}});
         g.doc["meshes"][0]["primitives"][0]["attributes"]["_FEATURE_ID_0"] = g.doc["accessors"].size() - 1;
       },
       "accessors[5]: 25 elements"},
      {"node cycle", [](GridGltf& g) { g.doc["nodes"][1]["children"] = {0}; }, "nodes[0]"},
      {"mode", [](GridGltf& g) { g.doc["meshes"][0]["primitives"][0]["mode"] = 9; }, "mode 9"},
      {"version", [](GridGltf& g) { g.doc["asset"]["version"] = "1.0"; }, "asset"},
      {"clamped UVs outside",
       [](GridGltf& g) {
         g.doc["samplers"] = {{{"wrapS", 33071}}};
         g.doc["textures"][0]["sampler"] = 0;
         g.doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]["KHR_texture_transform"] = {{"offset", {0.9, 0}}};
       },
       "wrap mode"},
      {"KTX2 without fallback",
       [](GridGltf& g) {
         g.doc["textures"][0] = {{"extensions", {{"KHR_texture_basisu", {{"source", 1}}}}}};
       },
       "textures[0]: KHR_texture_basisu"},
      {"unknown required extension", [](GridGltf& g) { g.doc["extensionsRequired"] = {"EXT_made_up"}; }, "EXT_made_up"},
      {"node matrix",
       [](GridGltf& g) {
         g.doc["nodes"][1]["matrix"] = {1, 0, 0};
       },
       "nodes[1]: matrix"},
      {"node rotation",
       [](GridGltf& g) {
         g.doc["nodes"][0]["rotation"] = {0, 0, 0, 0};
       },
       "nodes[0]: rotation"},
  };
}

TEST(GltfReader, RefusesEveryLieOnOneLineNamingTheFileAndElement) {
  const fs::path dir = scratch("lies");
  for (const Lie& lie : lies()) {
    GridGltf g = testing::grid_gltf();
    lie.change(g);
    const fs::path p = grid_glb(dir, g);
    try {
      read_gltf(p.string());
      ADD_FAILURE() << lie.name << ": read";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(p.string() + ": ", 0), 0u) << lie.name << ": " << what;
      EXPECT_NE(what.find(lie.element), std::string::npos) << lie.name << ": " << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << lie.name << ": " << what;
    }
  }
}

TEST(GltfReader, BoundsWhatSharedAccessorsMakeItRead) {
  // 300 primitives naming the same 2048 triangles: the bytes of the file do not grow with them, so
  // the corners read are bounded by the bytes (4 per byte, beyond a million) and the file refused.
  const fs::path dir = scratch("shared");
  GridGltf g = testing::grid_gltf(32);
  json& primitives = g.doc["meshes"][0]["primitives"];
  for (int i = 0; i < 300; ++i) primitives.push_back(primitives[0]);
  try {
    read_gltf(grid_glb(dir, g).string());
    ADD_FAILURE() << "300 primitives sharing one accessor were read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("shared by too many primitives"), std::string::npos) << e.what();
  }
  // A few sharing primitives are read, and each only once copies the vertices it uses.
  primitives.erase(primitives.begin() + 4, primitives.end());
  const TexturedMesh m = read_gltf(grid_glb(dir, g).string());
  EXPECT_EQ(m.num_triangles(), 3 * g.triangles);
  EXPECT_EQ(m.num_vertices(), 3 * 33u * 33u);
}

TEST(GltfReader, RefusesLyingGlbContainers) {
  const fs::path dir = scratch("container");
  const GridGltf g = testing::grid_gltf();
  const std::string good = testing::make_glb(g.doc, g.bin);
  std::vector<std::pair<const char*, std::string>> cases;
  std::string s = good;
  set_u32(s, 8, uint32_t(good.size() + 1));
  cases.push_back({"length beyond the file", s});
  s = good;
  set_u32(s, 12, uint32_t(good.size()));
  cases.push_back({"JSON chunk beyond the length", s});
  s = good;
  set_u32(s, 4, 1);
  cases.push_back({"version 1", s});
  const size_t bin_header = 20 + size_t(*reinterpret_cast<const uint32_t*>(&good[12]));
  s = good;
  set_u32(s, bin_header, uint32_t(good.size()));
  cases.push_back({"BIN chunk beyond the length", s});
  cases.push_back({"truncated", good.substr(0, 16)});
  s = testing::make_glb(json::object(), "");
  s[21] = ']';
  cases.push_back({"not JSON", s});
  for (const auto& [name, bytes] : cases) {
    write_file(dir / "c.glb", bytes);
    EXPECT_THROW(read_gltf((dir / "c.glb").string()), InputError) << name;
  }
}

/// The grid through the whole method at a small size.
Result optimized(const TexturedMesh& in) {
  Options opt;
  opt.size = 64;
  opt.map = MapKind::kArea;
  opt.aspect = 1.0;
  return optimize(in, opt);
}

TEST(GltfWriter, WritesTheInputDocumentBackWithEachTriangleInItsPrimitive) {
  const fs::path dir = scratch("roundtrip");
  const GridGltf g = testing::grid_gltf();
  const TexturedMesh in = read_gltf(grid_glb(dir, g).string());
  const Result r = optimized(in);
  for (const GltfContainer container : {GltfContainer::kGlb, GltfContainer::kGltf}) {
    const fs::path out = dir / (container == GltfContainer::kGlb ? "glb" : "gltf");
    const std::vector<std::string> removed = write_gltf(r.output, out.string(), "grid", ImageFormat::kPng, container);
    // The normal map reads the base colour's coordinates: re-baked, not removed.
    EXPECT_EQ(std::find(removed.begin(), removed.end(), "materials[0].normalTexture"), removed.end());
    const fs::path file = out / (container == GltfContainer::kGlb ? "grid.glb" : "grid.gltf");
    if (container == GltfContainer::kGltf) {
      EXPECT_TRUE(fs::exists(out / "grid.bin"));
      EXPECT_TRUE(fs::exists(out / "grid_tightex.png"));
    }
    ModelReadStats stats;
    const TexturedMesh back = read_gltf(file.string(), {}, &stats);
    const Metrics m = measure(in, back, 20000);
    EXPECT_EQ(m.lost_triangles, 0u);  // every triangle at its own positions, bit for bit
    EXPECT_EQ(m.flipped, 0u);
    EXPECT_EQ(back.num_triangles(), in.num_triangles());
    EXPECT_GT(m.surface_psnr, 30.0);
    const json& doc = back.gltf->json;
    EXPECT_EQ(doc["nodes"], g.doc["nodes"]);  // transforms and names as they were
    EXPECT_EQ(doc["scenes"], g.doc["scenes"]);
    EXPECT_EQ(doc["meshes"][0]["extras"], g.doc["meshes"][0]["extras"]);
    ASSERT_EQ(doc["materials"].size(), 1u);
    const json& mat = doc["materials"][0];
    for (const char* key : {"name", "doubleSided", "alphaMode", "alphaCutoff", "extras"})
      EXPECT_EQ(mat[key], g.doc["materials"][0][key]) << key;
    EXPECT_EQ(mat["pbrMetallicRoughness"]["baseColorFactor"], g.doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"]);
    ASSERT_TRUE(mat.contains("normalTexture"));
    EXPECT_EQ(mat["normalTexture"].value("texCoord", 0), 0);
    EXPECT_EQ(doc["images"].size(), 2u);  // the new base colour and normal map; the old images are gone
    EXPECT_TRUE(doc["meshes"][0]["primitives"][0]["attributes"].contains("TANGENT"));
    // The points primitive, as it came.
    ASSERT_EQ(stats.not_read.size(), 1u);
    const json& points = doc["meshes"][0]["primitives"][1];
    EXPECT_EQ(points["mode"], 0);
    const json& acc = doc["accessors"][points["attributes"]["POSITION"].get<size_t>()];
    const json& view = doc["bufferViews"][acc["bufferView"].get<size_t>()];
    const std::string_view buffer = back.gltf->buffers[0];
    EXPECT_EQ(buffer.substr(view["byteOffset"].get<size_t>(), 36), g.bin.substr(g.doc["bufferViews"][4]["byteOffset"].get<size_t>(), 36));
  }
}

using testing::expect_valid_and_loading;
using testing::node_check;
using testing::node_checks_ready;

/// Element `i` of accessor `a` of a document read by read_gltf, as raw bytes.
std::string accessor_element(const GltfDocument& doc, size_t a, size_t i) {
  const json& accessor = doc.json["accessors"][a];
  const size_t size =
      gltf_component_size(accessor["componentType"].get<int64_t>()) * gltf_type_components(accessor["type"].get<std::string>());
  if (!accessor.contains("bufferView")) return std::string(size, '\0');
  const json& view = doc.json["bufferViews"][accessor["bufferView"].get<size_t>()];
  const size_t stride = view.value("byteStride", size);
  const size_t offset = view.value("byteOffset", size_t(0)) + accessor.value("byteOffset", size_t(0)) + i * stride;
  return std::string(doc.buffers[view["buffer"].get<size_t>()].substr(offset, size));
}

TEST(GltfWriter, CarriesTheVertexAttributesItDoesNotChange) {
  // A 3D Tiles tile's _BATCHID (ushort: 2-byte elements, which need a byteStride of 4), a second UV set
  // and an all-zero accessor without a bufferView: each output vertex gets its input vertex's element.
  const fs::path dir = scratch("carried");
  testing::GridGltf g = testing::grid_gltf(6);
  const size_t count = g.doc["accessors"][0]["count"].get<size_t>();
  std::string batch, uv1;
  for (size_t v = 0; v < count; ++v)
    testing::append_bytes(batch, uint16_t(v % 7)), testing::append_bytes(uv1, float(v)), testing::append_bytes(uv1, 0.5f);
  auto add = [&](const std::string& bytes, int type, const char* kind) {
    while (g.bin.size() % 4 != 0) g.bin.push_back('\0');
    g.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", g.bin.size()}, {"byteLength", bytes.size()}});
    g.bin += bytes;
    g.doc["accessors"].push_back(
        {{"bufferView", g.doc["bufferViews"].size() - 1}, {"componentType", type}, {"count", count}, {"type", kind}});
    return g.doc["accessors"].size() - 1;
  };
  json& attributes = g.doc["meshes"][0]["primitives"][0]["attributes"];
  attributes["_BATCHID"] = add(batch, 5123, "SCALAR");
  attributes["TEXCOORD_1"] = add(uv1, 5126, "VEC2");
  g.doc["accessors"].push_back({{"componentType", 5126}, {"count", count}, {"type", "SCALAR"}});
  attributes["_ZERO"] = g.doc["accessors"].size() - 1;
  g.doc["buffers"][0]["byteLength"] = g.bin.size();
  const TexturedMesh in = read_gltf(grid_glb(dir, g).string());
  const std::vector<std::string> removed = write_gltf(optimized(in).output, dir.string(), "out", ImageFormat::kPng, GltfContainer::kGlb);
  for (const std::string& r : removed) EXPECT_EQ(r.find("attribute"), std::string::npos) << r;
  const TexturedMesh back = read_gltf((dir / "out.glb").string());
  const GltfDocument& doc = *back.gltf;
  size_t checked = 0;
  for (const json& p : doc.json["meshes"][0]["primitives"]) {
    if (p.value("mode", 4) != 4) continue;
    const json& a = p["attributes"];
    ASSERT_TRUE(a.contains("_BATCHID") && a.contains("TEXCOORD_1") && a.contains("_ZERO")) << a.dump();
    const size_t n = doc.json["accessors"][a["POSITION"].get<size_t>()]["count"].get<size_t>();
    for (size_t v = 0; v < n; ++v) {
      // The input vertex at this position: the grid's x and y give its column and row.
      float x, y, u;
      uint16_t id;
      std::memcpy(&x, accessor_element(doc, a["POSITION"].get<size_t>(), v).data(), 4);
      std::memcpy(&y, accessor_element(doc, a["POSITION"].get<size_t>(), v).data() + 4, 4);
      const size_t input_vertex = size_t(std::lround(y * 7.0f)) * 7 + size_t(std::lround((x - 0.1f) * 3.0f));
      std::memcpy(&id, accessor_element(doc, a["_BATCHID"].get<size_t>(), v).data(), 2);
      std::memcpy(&u, accessor_element(doc, a["TEXCOORD_1"].get<size_t>(), v).data(), 4);
      EXPECT_EQ(id, input_vertex % 7) << v;
      EXPECT_EQ(u, float(input_vertex)) << v;
      EXPECT_EQ(accessor_element(doc, a["_ZERO"].get<size_t>(), v), std::string(4, '\0'));
      ++checked;
    }
  }
  EXPECT_GE(checked, count);                                          // every input vertex, some twice (split along the cut)
  expect_valid_and_loading(dir / "out.glb", 2 * in.num_triangles());  // two nodes show the mesh
}

TEST(GltfReader, ReadsQuantizedPositionsAndNormals) {
  // KHR_mesh_quantization as gltfpack writes it: int16 positions (a stride of 8), normalized int8
  // normals (a stride of 4); the node's scale brings them to metres. Written back as floats, the same
  // values, with the extension still declared (points and carried attributes may use it).
  const fs::path dir = scratch("quantized");
  testing::GridGltf g = testing::grid_gltf(4);
  const size_t count = g.doc["accessors"][0]["count"].get<size_t>();
  std::string pos, nor;
  for (size_t v = 0; v < count; ++v) {
    for (int16_t x : {int16_t(300 * (v % 5)), int16_t(700 * (v / 5)), int16_t(v % 2), int16_t(0)}) testing::append_bytes(pos, x);
    for (int8_t x : {int8_t(0), int8_t(0), int8_t(127), int8_t(0)}) testing::append_bytes(nor, x);
  }
  auto add = [&](const std::string& bytes, int stride, json accessor) {
    while (g.bin.size() % 4 != 0) g.bin.push_back('\0');
    g.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", g.bin.size()}, {"byteLength", bytes.size()}, {"byteStride", stride}});
    g.bin += bytes;
    accessor["bufferView"] = g.doc["bufferViews"].size() - 1;
    accessor["count"] = count;
    g.doc["accessors"].push_back(accessor);
    return g.doc["accessors"].size() - 1;
  };
  json& attributes = g.doc["meshes"][0]["primitives"][0]["attributes"];
  attributes["POSITION"] = add(pos, 8, {{"componentType", 5122}, {"type", "VEC3"}, {"min", {0, 0, 0}}, {"max", {1200, 2800, 1}}});
  attributes["NORMAL"] = add(nor, 4, {{"componentType", 5120}, {"normalized", true}, {"type", "VEC3"}});
  g.doc["buffers"][0]["byteLength"] = g.bin.size();
  g.doc["extensionsUsed"] = {"KHR_mesh_quantization"};
  g.doc["extensionsRequired"] = {"KHR_mesh_quantization"};
  const TexturedMesh in = read_gltf(grid_glb(dir, g).string());
  ASSERT_EQ(in.num_triangles(), g.triangles);
  EXPECT_EQ(in.positions[1], Vec3(300, 0, 1));
  EXPECT_NEAR(in.corner_normal[0].z(), 1.0, 1e-12);
  write_gltf(optimized(in).output, dir.string(), "out", ImageFormat::kPng, GltfContainer::kGlb);
  const TexturedMesh back = read_gltf((dir / "out.glb").string());
  EXPECT_EQ(measure(in, back, 20000).lost_triangles, 0u);
  EXPECT_EQ(back.gltf->json["extensionsRequired"], json({"KHR_mesh_quantization"}));
  expect_valid_and_loading(dir / "out.glb", 2 * in.num_triangles());
  // Without the extension declared, integer positions are refused on one line that names it.
  g.doc.erase("extensionsUsed"), g.doc.erase("extensionsRequired");
  const fs::path plain = grid_glb(dir, g);
  try {
    read_gltf(plain.string());
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("KHR_mesh_quantization"), std::string::npos) << e.what();
  }
}

TEST(GltfWriter, WritesAFreshDocumentForAnotherModel) {
  const fs::path dir = scratch("fresh");
  TexturedMesh m = testing::multi_component();
  for (Vec3& p : m.positions) p += Vec3(1e-9, 0, 0);  // not float32 values: glTF rounds them
  write_gltf(m, dir.string(), "cat", ImageFormat::kPng, GltfContainer::kGlb);
  const TexturedMesh back = read_gltf((dir / "cat.glb").string());
  EXPECT_EQ(back.num_triangles(), m.num_triangles());
  const Metrics met = measure(m, back, 20000);
  EXPECT_EQ(met.lost_triangles, 0u) << "the same positions, as float32 stores them";
  TexturedMesh moved = back;
  moved.positions[moved.triangles[0][0]].x() += 1e-3;
  EXPECT_GE(measure(m, moved, 20000).lost_triangles, 1u) << "a moved corner is a lost triangle";
  EXPECT_EQ(met.flipped, measure(m, m, 20000).flipped);  // the texture coordinates as they were
  EXPECT_EQ(back.materials.size(), m.materials.size());
  for (size_t t = 0; t < m.num_triangles(); t += 97)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR((back.corner_uv[3 * t + size_t(k)] - m.sampled_uv(t, k)).norm(), 0.0, 1e-6);
}

// ---------------------------------------------------------------------------------------------------
// The command line, and the written files in the Khronos glTF-Validator and three.js (tests/gltf).

TEST(GltfValidator, WrittenFilesHaveNoErrorNorWarningAndLoadInThree) {
  const fs::path dir = scratch("validator");
  const TexturedMesh in = read_gltf(grid_glb(dir).string());
  const Result r = optimized(in);
  write_gltf(r.output, (dir / "glb").string(), "grid", ImageFormat::kPng, GltfContainer::kGlb);
  write_gltf(r.output, (dir / "gltf").string(), "grid", ImageFormat::kJpeg, GltfContainer::kGltf);
  write_gltf(testing::multi_component(), (dir / "fresh").string(), "cat", ImageFormat::kPng, GltfContainer::kGlb);
  // Two nodes show the grid's mesh: three.js counts its triangles twice.
  expect_valid_and_loading(dir / "glb" / "grid.glb", 2 * in.num_triangles());
  expect_valid_and_loading(dir / "gltf" / "grid.gltf", 2 * in.num_triangles());
  expect_valid_and_loading(dir / "fresh" / "cat.glb", testing::multi_component().num_triangles());
}

/// The CLI on `input` (glTF out by default): its report, after checking lost 0, flipped 0 and one chart
/// per component, and the written file in the validator.
json run_and_check(const fs::path& input, const fs::path& out, const std::string& options = "") {
  const int rc = testing::run_tightex("'" + input.string() + "' -o '" + out.string() + "' --quiet " + options);
  EXPECT_EQ(rc, 0);
  const json report = json::parse(read_file(out / "report.json"));
  EXPECT_EQ(report["metrics"]["lost_triangles"], 0);
  EXPECT_EQ(report["metrics"]["flipped"], 0);
  EXPECT_EQ(report["metrics"]["charts"], report["preparation"]["components"]);
  return report;
}

TEST(GltfRealData, KhronosGlbModelsGiveGlbs) {
  for (const char* model : {"khronos_avocado/Avocado.glb", "khronos_waterbottle/WaterBottle.glb"}) {
    const fs::path input = fs::path(TIGHTEX_SHARED_DATA) / model;
    if (!fs::exists(input)) GTEST_SKIP() << input << " is absent";
    const fs::path out = scratch(input.stem().string());
    const json report = run_and_check(input, out);
    ASSERT_TRUE(fs::exists(out / (input.stem().string() + ".glb")));
    const TexturedMesh in = read_gltf(input.string()), back = read_gltf((out / (input.stem().string() + ".glb")).string());
    const Metrics m = measure(in, back, 20000);
    EXPECT_EQ(m.lost_triangles, 0u) << model;  // read back from the file: positions bit for bit
    EXPECT_GE(m.output.utilization, 0.99) << model;
    EXPECT_EQ(back.gltf->json["nodes"], in.gltf->json["nodes"]) << model;
    // Every map slot of the input, in the output; normals through both TANGENTs.
    EXPECT_EQ(back.corner_tangent.size(), 3 * back.num_triangles()) << model;
    size_t normal_maps = 0;
    for (const MaterialMapFigures& f : m.maps) {
      if (f.slot != MaterialSlot::kNormal) continue;
      ++normal_maps;
      EXPECT_LT(f.angle_median, 2.0) << model;
      EXPECT_LT(f.angle_p95, 8.0) << model;
    }
    EXPECT_EQ(normal_maps, 1u) << model;
    for (size_t s = 0; s < kMaterialSlots; ++s)
      EXPECT_EQ(in.materials[0].maps[s] >= 0, back.materials[0].maps[s] >= 0) << model << " " << material_slot_name(MaterialSlot(s));
    expect_valid_and_loading(out / (input.stem().string() + ".glb"), in.num_triangles());
  }
}

TEST(GltfCli, AnObjScanConvertedToGlbGoesThrough) {
  const fs::path obj = fs::path(TIGHTEX_SHARED_DATA) / "fuze" / "fuze.obj";
  if (!fs::exists(obj)) GTEST_SKIP() << obj << " is absent";
  const fs::path dir = scratch("fuze");
  TexturedMesh scan = read_obj(obj.string());
  for (Vec3& p : scan.positions) p = Vec3(float(p.x()), float(p.y()), float(p.z()));
  write_gltf(scan, (dir / "in").string(), "fuze", ImageFormat::kJpeg, GltfContainer::kGlb);
  const json report = run_and_check(dir / "in" / "fuze.glb", dir / "out", "--size 256");
  EXPECT_EQ(report["input"]["triangles"], scan.num_triangles());
  expect_valid_and_loading(dir / "out" / "fuze.glb", scan.num_triangles());
  // And --output-format obj from a glTF input: an OBJ beside nothing else.
  EXPECT_EQ(testing::run_tightex("'" + (dir / "in" / "fuze.glb").string() + "' -o '" + (dir / "obj").string() +
                                 "' --quiet --size 64 --output-format obj"),
            0);
  EXPECT_TRUE(fs::exists(dir / "obj" / "fuze.obj"));
}

TEST(GltfCli, RefusesHostileFilesWithExitOneAndNothingWritten) {
  const fs::path dir = scratch("hostile");
  std::vector<std::pair<std::string, std::string>> files;
  for (const Lie& lie : lies()) {
    GridGltf g = testing::grid_gltf();
    lie.change(g);
    files.push_back({lie.name, testing::make_glb(g.doc, g.bin)});
  }
  // A PNG whose header declares 200000 x 200000 pixels: refused from its header by --max-memory.
  GridGltf huge = testing::grid_gltf();
  std::string png = testing::gradient_png();
  const uint32_t side = __builtin_bswap32(200000u);
  std::memcpy(&png[16], &side, 4), std::memcpy(&png[20], &side, 4);
  huge.doc["images"][0] = {{"uri", "big.png"}};
  write_file(dir / "big.png", png);
  files.push_back({"huge texture header", testing::make_glb(huge.doc, huge.bin)});
  // Nothing to bake: no texture, no vertex colours.
  GridGltf plain = testing::grid_gltf();
  plain.doc["materials"][0].erase("pbrMetallicRoughness");
  files.push_back({"nothing to bake", testing::make_glb(plain.doc, plain.bin)});
  for (const auto& [name, bytes] : files) {
    const fs::path input = dir / "in.glb", out = dir / "out", err = dir / "err.txt";
    write_file(input, bytes);
    fs::remove_all(out);
    EXPECT_EQ(
        testing::run_tightex("'" + input.string() + "' -o '" + out.string() + "' --quiet --max-memory 4096 2> '" + err.string() + "'"), 1)
        << name;
    const std::string message = read_file(err);
    EXPECT_EQ(std::count(message.begin(), message.end(), '\n'), 1) << name << ": " << message;
    EXPECT_NE(message.find(input.string()), std::string::npos) << name << ": " << message;
    EXPECT_FALSE(fs::exists(out / "in.glb")) << name;
  }
}

}  // namespace
}  // namespace tightex
