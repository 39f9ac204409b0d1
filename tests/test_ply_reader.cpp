// Tests for the PLY reader: small files written in code in ascii, binary little endian and binary big
// endian (per-face texcoords with two texture pages and texnumber, per-vertex texture coordinates under
// each of their names, quads, every scalar type, skipped elements and properties), a table of hostile
// files that must be refused with one line naming the file, and a catalogue mesh written as PLY that
// goes through optimize and through the command line.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.hpp"
#include "io/image_io.hpp"
#include "io/ply_reader.hpp"
#include "mesh_catalogue.hpp"
#include "report/metrics.hpp"
#include "report/report.hpp"
#include "tightex/io.hpp"
#include "tightex/tightex.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;
namespace cat = tightex::testing;

enum class Format { kAscii, kLittle, kBig };

const char* format_name(Format f) {
  return f == Format::kAscii ? "ascii" : f == Format::kLittle ? "binary_little_endian" : "binary_big_endian";
}

/// A PLY file built in code: header lines, then values written as the format wants them (ascii: text
/// separated by blanks, one entry a line; binary: the value's bytes in the file's byte order).
class PlyBuilder {
 public:
  explicit PlyBuilder(Format format) : format_(format) { header_ = fmt::format("ply\nformat {} 1.0\n", format_name(format)); }

  PlyBuilder& header(const std::string& line) {
    header_ += line + "\n";
    return *this;
  }
  template <typename T>
  PlyBuilder& put(T v) {
    if (format_ == Format::kAscii) {
      if constexpr (sizeof(T) == 1)
        body_ += fmt::format("{} ", int(v));
      else
        body_ += fmt::format("{} ", v);
      return *this;
    }
    char bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));
    const bool swap = (format_ == Format::kBig) != (std::endian::native == std::endian::big);
    if (swap)
      for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
    body_.append(bytes, sizeof(T));
    return *this;
  }
  /// Ends one element entry (a new line in ascii).
  PlyBuilder& end() {
    if (format_ == Format::kAscii) body_ += "\n";
    return *this;
  }
  std::string str() const { return header_ + "end_header\n" + body_; }

 private:
  Format format_;
  std::string header_, body_;
};

/// A fresh folder per test, removed afterwards.
class PlyReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("tightex_ply_reader_") + info->name() + "_" + std::to_string(::getpid());
    for (char& c : name)
      if (c == '/') c = '_';
    dir_ = fs::temp_directory_path() / name;
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string write(const std::string& name, const std::string& bytes) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << bytes;
    return p.string();
  }
  void write_image(const std::string& name, int w, int h) {
    Image img(w, h);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) img.at(x, y) = {uint8_t(40 * x), uint8_t(40 * y), 7, 255};
    save_image((dir_ / name).string(), img, ImageFormat::kPng);
  }

  /// The message read_ply throws, or "" when it reads the file. Every message is one line.
  static std::string error_of(const std::string& path, const ModelReadOptions& options = {}) {
    try {
      read_ply(path, options);
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      return message;
    }
    return "";
  }

  fs::path dir_;
};

// ---- the same textured model in each format ----

// Five vertices; a triangle on page 0 and a quad on page 1. Dyadic values are exact in every type; one
// texture coordinate is 0.1, which float32 cannot hold: binary files must give double(0.1f) exactly.
constexpr double kPositions[5][3] = {{0, 0, 0}, {1.5, 0, 0}, {1.5, 2.25, 0}, {0, 2.25, -0.5}, {-1, 1, 0.125}};
constexpr double kTriangleUv[6] = {0.1, 0.25, 0.5, 0.25, 0.5, 0.75};
constexpr double kQuadUv[8] = {0.125, 0.5, 0.875, 0.5, 0.875, 1.0, 0.125, 1.0};
// Each of them as a float32 reads back, written out: computed as double(float(t)) inside the checking
// loop, the GCC 12 -O3 build gave 0.1 itself (not so under valgrind; not understood).
const std::map<double, double> kAsFloat32 = {{0.1, double(0.1f)}, {0.25, 0.25},   {0.5, 0.5}, {0.75, 0.75},
                                             {0.125, 0.125},      {0.875, 0.875}, {1.0, 1.0}};

std::string textured_model(Format format) {
  PlyBuilder b(format);
  b.header("comment made by a test")
      .header("comment TextureFile page_a.png")
      .header("comment TextureFile page b.png")
      .header("element vertex 5")
      .header("property double x")
      .header("property double y")
      .header("property double z")
      .header("property uchar red")
      .header("property uchar green")
      .header("property uchar blue")
      .header("element face 2")
      .header("property list uchar int vertex_indices")
      .header("property list uchar float texcoord")
      .header("property int texnumber");
  for (const auto& p : kPositions) b.put(p[0]).put(p[1]).put(p[2]).put(uint8_t(200)).put(uint8_t(100)).put(uint8_t(50)).end();
  b.put(uint8_t(3)).put(int32_t(0)).put(int32_t(1)).put(int32_t(2)).put(uint8_t(6));
  for (double t : kTriangleUv) b.put(float(t));
  b.put(int32_t(0)).end();
  b.put(uint8_t(4)).put(int32_t(0)).put(int32_t(2)).put(int32_t(3)).put(int32_t(4)).put(uint8_t(8));
  for (double t : kQuadUv) b.put(float(t));
  b.put(int32_t(1)).end();
  return b.str();
}

class PlyFormats : public PlyReaderTest, public ::testing::WithParamInterface<Format> {};

TEST_P(PlyFormats, PerFaceTexcoordsOnTwoPages) {
  write_image("page_a.png", 2, 3);
  write_image("page b.png", 4, 1);
  const std::string path = write("model.ply", textured_model(GetParam()));
  ModelReadStats stats;
  const TexturedMesh m = read_ply(path, {}, &stats);
  ASSERT_EQ(m.positions.size(), 5u);
  for (size_t v = 0; v < 5; ++v) EXPECT_EQ(m.positions[v], Vec3(kPositions[v][0], kPositions[v][1], kPositions[v][2])) << v;
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Tri{0, 2, 3}));
  EXPECT_EQ(m.triangles[2], (Tri{0, 3, 4}));
  EXPECT_EQ(stats.polygons_triangulated, 1u);
  // Binary floats arrive bit-exact; ascii text reads as the double it spells.
  const bool binary = GetParam() != Format::kAscii;
  auto stored = [&](size_t i, const double* uv) { return binary ? kAsFloat32.at(uv[i]) : uv[i]; };
  ASSERT_EQ(m.corner_uv.size(), 9u);
  for (size_t k = 0; k < 3; ++k) {
    const Vec2 expected(stored(2 * k, kTriangleUv), stored(2 * k + 1, kTriangleUv));
    EXPECT_EQ(m.corner_uv[k], expected) << k;
  }
  const int quad_corner[6] = {0, 1, 2, 0, 2, 3};  // the fan's corners in the quad
  for (int c = 0; c < 6; ++c) {
    const int q = quad_corner[c];
    EXPECT_EQ(m.corner_uv[size_t(3 + c)], Vec2(stored(size_t(2 * q), kQuadUv), stored(size_t(2 * q + 1), kQuadUv))) << c;
  }
  EXPECT_EQ(m.corner_uv[0].x(), binary ? double(0.1f) : 0.1);
  EXPECT_EQ(m.face_material, (std::vector<int32_t>{0, 1, 1}));
  ASSERT_EQ(m.materials.size(), 2u);
  ASSERT_EQ(m.textures.size(), 2u);
  EXPECT_EQ(m.materials[0].texture, 0);
  EXPECT_EQ(m.materials[1].texture, 1);
  EXPECT_EQ(m.textures[0].image.width, 2);
  EXPECT_EQ(m.textures[1].image.width, 4);
  EXPECT_EQ(fs::path(m.textures[1].path).filename(), "page b.png");
  EXPECT_EQ(m.source, path);
}

/// A unit square as one quad with per-vertex texture coordinates named `u` and `v`, the vertex's
/// properties in an odd order and the elements after a skipped one.
std::string per_vertex_square(Format format, const std::string& u, const std::string& v) {
  PlyBuilder b(format);
  b.header("comment TextureFile tex.png")
      .header("element camera 1")
      .header("property float view_px")
      .header("property list uint int junk")
      .header("element vertex 4")
      .header("property float " + u)
      .header("property float z")
      .header("property float nx")
      .header("property float y")
      .header("property float x")
      .header("property float " + v)
      .header("element face 1")
      .header("property uchar flags")
      .header("property list uchar uint vertex_index")
      .header("element nothing 1000000000000");  // no properties: takes no bytes
  b.put(3.5f).put(uint32_t(2)).put(int32_t(-7)).put(int32_t(9)).end();
  const float corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const auto& c : corners) b.put(c[0] * 0.5f).put(0.0f).put(1.0f).put(c[1]).put(c[0]).put(c[1] * 0.25f + 0.1f).end();
  b.put(uint8_t(0)).put(uint8_t(4)).put(uint32_t(0)).put(uint32_t(1)).put(uint32_t(2)).put(uint32_t(3)).end();
  return b.str();
}

TEST_P(PlyFormats, PerVertexTextureCoordinatesUnderEachName) {
  write_image("tex.png", 3, 3);
  for (const auto& [u, v] : {std::pair{"s", "t"}, {"u", "v"}, {"texture_u", "texture_v"}}) {
    const std::string path = write(std::string("square_") + u + ".ply", per_vertex_square(GetParam(), u, v));
    ModelReadStats stats;
    const TexturedMesh m = read_ply(path, {}, &stats);
    ASSERT_EQ(m.triangles.size(), 2u) << u;
    EXPECT_EQ(stats.polygons_triangulated, 1u);
    EXPECT_EQ(m.positions[2], Vec3(1, 1, 0));
    const bool binary = GetParam() != Format::kAscii;
    for (size_t c = 0; c < 6; ++c) {
      const uint32_t vertex = m.triangles[c / 3][c % 3];
      const float fu = float(m.positions[vertex].x()) * 0.5f, fv = float(m.positions[vertex].y()) * 0.25f + 0.1f;
      // Ascii writes each float in its shortest form, which reads back as the double nearest to it.
      const Vec2 expected = binary ? Vec2(fu, fv) : Vec2(std::stod(fmt::format("{}", fu)), std::stod(fmt::format("{}", fv)));
      EXPECT_EQ(m.corner_uv[c], expected) << u << " corner " << c;
    }
    EXPECT_EQ(m.face_material, (std::vector<int32_t>{0, 0}));  // no texnumber: the first page
    EXPECT_EQ(m.textures.at(0).image.width, 3);
  }
}

TEST_P(PlyFormats, EveryScalarTypeUnderBothNames) {
  PlyBuilder b(GetParam());
  b.header("element face 1")
      .header("property list int8 uint16 vertex_indices")
      .header("property list ushort double texcoord")
      .header("element vertex 3")
      .header("property char x")
      .header("property uint8 y")
      .header("property int16 z")
      .header("property short a")
      .header("property uint16 b")
      .header("property int32 c")
      .header("property uint d")
      .header("property float32 e")
      .header("property float64 f")
      .header("property list int uchar g");
  b.put(int8_t(3)).put(uint16_t(2)).put(uint16_t(0)).put(uint16_t(1)).put(uint16_t(6));
  for (double t : {0.25, 0.5, 0.75, 0.125, 0.375, 0.625}) b.put(t);
  b.end();
  const int8_t xs[3] = {-128, 0, 127};
  const uint8_t ys[3] = {255, 0, 1};
  const int16_t zs[3] = {-32768, 32767, 5};
  for (int i = 0; i < 3; ++i)
    b.put(xs[i])
        .put(ys[i])
        .put(zs[i])
        .put(int16_t(-1))
        .put(uint16_t(65535))
        .put(int32_t(-2))
        .put(uint32_t(4000000000u))
        .put(1.5f)
        .put(-2.5)
        .put(int32_t(2))
        .put(uint8_t(1))
        .put(uint8_t(2))
        .end();
  const std::string path = write("types.ply", b.str());
  const TexturedMesh m = read_ply(path);
  ASSERT_EQ(m.positions.size(), 3u);
  EXPECT_EQ(m.positions[0], Vec3(-128, 255, -32768));
  EXPECT_EQ(m.positions[1], Vec3(0, 0, 32767));
  EXPECT_EQ(m.triangles.at(0), (Tri{2, 0, 1}));
  EXPECT_EQ(m.corner_uv.at(2), Vec2(0.375, 0.625));
  EXPECT_EQ(m.face_material, (std::vector<int32_t>{-1}));  // no TextureFile: no material
  EXPECT_TRUE(m.materials.empty());
}

INSTANTIATE_TEST_SUITE_P(AllFormats, PlyFormats, ::testing::Values(Format::kAscii, Format::kLittle, Format::kBig),
                         [](const auto& info) { return std::string(format_name(info.param)); });

// ---- files and textures ----

TEST_F(PlyReaderTest, TextureFoundWithoutCaseAndReported) {
  write_image("Page_A.PNG", 2, 2);
  write_image("page b.png", 1, 1);
  const std::string path = write("model.ply", textured_model(Format::kLittle));
  ModelReadStats stats;
  const TexturedMesh m = read_ply(path, {}, &stats);
  EXPECT_EQ(m.textures.at(0).image.width, 2);
  ASSERT_EQ(stats.paths_found.size(), 1u);
  EXPECT_NE(stats.paths_found[0].find("page_a.png -> "), std::string::npos) << stats.paths_found[0];
}

TEST_F(PlyReaderTest, MissingTextureNamesTheHeaderLine) {
  write_image("page_a.png", 2, 2);
  const std::string path = write("model.ply", textured_model(Format::kAscii));
  const std::string message = error_of(path);
  EXPECT_NE(message.find(path + ":5: texture 'page b.png'"), std::string::npos) << message;
  ModelReadOptions no_textures;
  no_textures.load_textures = false;
  const TexturedMesh m = read_ply(path, no_textures);  // paths only: nothing to load
  EXPECT_TRUE(m.textures.at(1).image.empty());
}

TEST_F(PlyReaderTest, ReadModelDispatchesOnTheExtensionWithoutCase) {
  write_image("page_a.png", 2, 2);
  write_image("page b.png", 1, 1);
  const std::string ply = write("MODEL.PLY", textured_model(Format::kBig));
  EXPECT_EQ(read_model(ply).num_triangles(), 3u);
  const std::string obj = write("model.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
  EXPECT_EQ(read_model(obj).num_triangles(), 1u);
}

// ---- hostile and broken files ----

struct Hostile {
  const char* name;
  std::string bytes;
  const char* problem;  // part of the message
};

// A valid ascii file: two vertices too few for a lie to go unnoticed, a triangle with texcoords.
const std::string kHead = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
const std::string kFace = "element face 1\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n";
const std::string kVerts = "0 0 0\n1 0 0\n0 1 0\n";
const std::string kTexcoords = " 6 0 0 1 0 0 1\n";

std::string binary_header(const std::string& elements) { return "ply\nformat binary_little_endian 1.0\n" + elements + "end_header\n"; }

std::vector<Hostile> hostile_files() {
  const std::string valid = kHead + kFace + kVerts + "3 0 1 2" + kTexcoords;
  std::string nan_float(4, '\0');
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan_float.data(), &nan, 4);
  const std::string xyz_float = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string face_list = "element face 1\nproperty list uint int vertex_indices\nproperty list uchar float texcoord\n";
  return {
      {"empty", "", "not a PLY file"},
      {"obj text", "v 0 0 0\n", "not a PLY file"},
      {"no end_header", "ply\nformat ascii 1.0\nelement vertex 3\n", "no end_header"},
      {"no format",
       "ply\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int "
       "vertex_indices\nproperty list uchar float texcoord\nend_header\n",
       "no format line"},
      {"unknown format", "ply\nformat binary_middle_endian 1.0\nend_header\n", "unknown format"},
      {"unknown type", kHead + "property float128 w\n" + kFace + kVerts, "unknown property type 'float128'"},
      {"float list size", kHead + "element face 1\nproperty list float int vertex_indices\nend_header\n", "list size of type float"},
      {"property first", "ply\nformat ascii 1.0\nproperty float x\nend_header\n", "property before any element"},
      {"unknown header line", kHead + "frobnicate 3\n" + kFace, "unknown header line"},
      {"second element", kHead + "element vertex 3\n" + kFace, "second element 'vertex'"},
      {"second property", kHead + "property float y\n" + kFace, "second property 'y'"},
      {"malformed count", "ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n", "malformed count"},
      {"no x",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
       "no property 'x'"},
      {"point cloud", kHead + "end_header\n" + kVerts, "no 'face' element"},
      {"float indices", kHead + "element face 1\nproperty list uchar float vertex_indices\nend_header\n", "list of integers"},
      {"no texcoords", kHead + "element face 1\nproperty list uchar int vertex_indices\nend_header\n" + kVerts + "3 0 1 2\n",
       "neither texture coordinates"},
      {"TextureFile without name", "ply\nformat ascii 1.0\ncomment TextureFile  \nend_header\n", "without a file name"},
      {"ascii count lie",
       "ply\nformat ascii 1.0\nelement vertex 3000000000\nproperty float x\nproperty float y\nproperty float z\n" + kFace + kVerts,
       "more than the"},
      {"binary count lie",
       binary_header(xyz_float.substr(0, 15) + "100000000\nproperty float x\nproperty float y\nproperty float z\n" + face_list) +
           std::string(64, '\0'),
       "more than the"},
      {"binary face count lie",
       binary_header(xyz_float + "element face 18446744073709551615\nproperty list uint int vertex_indices\n") + std::string(12, '\0'),
       "more than the"},
      {"truncated ascii", kHead + kFace + kVerts + "3 0 1 2 6 0 0", "truncated"},
      {"truncated binary", binary_header(xyz_float + face_list) + std::string(12, '\0') + std::string("\x03\0\0\0\0\0\0\0", 8),
       "truncated"},
      {"huge skipped list",
       binary_header("element junk 1\nproperty list uint uchar stuff\n" + xyz_float + face_list) + std::string("\xff\xff\xff\xff", 4) +
           std::string(40, '\0'),
       "truncated"},
      {"list too long",
       kHead + "element face 1\nproperty list ushort int vertex_indices\nproperty list uchar float texcoord\nend_header\n" + kVerts +
           "2000 0 1 2\n",
       "at most 1024"},
      {"negative list size",
       kHead + "element face 1\nproperty list char int vertex_indices\nproperty list uchar float texcoord\nend_header\n" + kVerts +
           "-3 0 1 2" + kTexcoords,
       "negative size"},
      {"two corners", kHead + kFace + kVerts + "2 0 1 4 0 0 1 0\n", "needs at least 3"},
      {"index out of range", kHead + kFace + kVerts + "3 0 1 3" + kTexcoords, "vertex index 3 out of range"},
      {"negative index", kHead + kFace + kVerts + "3 0 -1 2" + kTexcoords, "vertex index -1 out of range"},
      {"fractional index", kHead + kFace + kVerts + "3 0 1.5 2" + kTexcoords, "not a value of type int"},
      {"uchar out of range", kHead + kFace + kVerts + "256 0 1 2" + kTexcoords, "not a value of type uchar"},
      {"malformed number", kHead + kFace + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2" + kTexcoords, "malformed number 'zero'"},
      {"ascii NaN", kHead + kFace + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2" + kTexcoords, "NaN or infinite coordinate"},
      {"binary NaN", binary_header(xyz_float + face_list) + nan_float + std::string(8, '\0') + std::string(12, '\0'),
       "NaN or infinite coordinate"},
      {"absurd coordinate", kHead + kFace + "0 0 0\n1 1e300 0\n0 1 0\n3 0 1 2" + kTexcoords, "absurd coordinate"},
      {"NaN texcoord", kHead + kFace + kVerts + "3 0 1 2 6 0 0 1 nan 0 1\n", "NaN or infinite texture coordinate"},
      {"texcoord count", kHead + kFace + kVerts + "3 0 1 2 4 0 0 1 0\n", "texcoord list of 4 values"},
      {"texnumber out of range",
       kHead + "comment TextureFile a.png\n" + kFace.substr(0, kFace.size() - 11) + "property int texnumber\nend_header\n" + kVerts +
           "3 0 1 2 6 0 0 1 0 0 1 1\n",
       "texnumber 1 out of range"},
      {"texnumber without pages",
       kHead + kFace.substr(0, kFace.size() - 11) + "property uchar texnumber\nend_header\n" + kVerts + "3 0 1 2 6 0 0 1 0 0 1 0\n",
       "texnumber 0 out of range (the header names 0 texture files)"},
      {"missing texture", kHead + "comment TextureFile nowhere.png\n" + kFace + kVerts + "3 0 1 2" + kTexcoords,
       "texture 'nowhere.png' (comment TextureFile) could not be loaded"},
      {"no faces",
       kHead + "element face 0\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n" + kVerts,
       "no faces"},
      {"the valid file, for reference", valid, ""},
  };
}

TEST_F(PlyReaderTest, HostileFilesAreRefusedWithOneLineNamingTheFile) {
  int i = 0;
  for (const Hostile& h : hostile_files()) {
    const std::string path = write("hostile_" + std::to_string(i++) + ".ply", h.bytes);
    const std::string message = error_of(path);
    if (std::string(h.problem).empty()) {
      EXPECT_EQ(message, "") << h.name;
      continue;
    }
    EXPECT_EQ(message.rfind(path, 0), 0u) << h.name << ": " << message;
    EXPECT_NE(message.find(h.problem), std::string::npos) << h.name << ": " << message;
  }
}

// The pages of a model read without pixels, decoded later (load_texture_pixels, as the CLI does beside
// the geometric stages): the pixels a read with them gives, and for a page that cannot be loaded the
// same one-line error, naming its TextureFile line.
TEST_F(PlyReaderTest, PagesDecodedAfterTheReadAreThoseTheReadGives) {
  write_image("page_a.png", 2, 3);
  const std::string path = write("model.ply", textured_model(Format::kAscii));
  ModelReadOptions geometry_only;
  geometry_only.load_textures = false;
  const TexturedMesh geometry = read_ply(path, geometry_only);
  ASSERT_EQ(geometry.textures.size(), 2u);
  const std::string message = error_of(path);
  EXPECT_EQ(message.rfind(path + ":5: texture 'page b.png' (comment TextureFile) could not be loaded: ", 0), 0u) << message;
  try {
    load_texture_pixels(geometry);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
  write_image("page b.png", 4, 1);
  const TexturedMesh full = read_ply(path);
  const std::vector<Texture> decoded = load_texture_pixels(geometry);
  ASSERT_EQ(decoded.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(decoded[i].path, full.textures[i].path);
    EXPECT_EQ(decoded[i].image.width, full.textures[i].image.width);
    EXPECT_EQ(decoded[i].image.pixels, full.textures[i].image.pixels);
  }
}

TEST_F(PlyReaderTest, BodyErrorsNameTheElementEntryAndAsciiLine) {
  const std::string ascii = write("a.ply", kHead + kFace + kVerts + "3 0 1 7" + kTexcoords);
  EXPECT_EQ(error_of(ascii), ascii + ":14: face 0: vertex index 7 out of range (the file has 3 vertices)");
  PlyBuilder b(Format::kBig);
  b.header("element vertex 2").header("property float x").header("property float y").header("property float z");
  b.header("element face 1").header("property list uchar uint vertex_indices").header("property list uchar float texcoord");
  b.put(0.f).put(0.f).put(0.f).put(1.f).put(std::numeric_limits<float>::infinity()).put(0.f);
  const std::string binary = write("b.ply", b.str() + std::string(8, '\0'));
  EXPECT_EQ(error_of(binary), binary + ": vertex 1: NaN or infinite coordinate");
}

// ---- large ascii files: vertices and faces read in blocks of lines on every core ----

/// A sheet of n x n vertices in `format`, per-face texcoords, every 7th cell a quad and the others two
/// triangles (dyadic values: exact in float32 and in text). `irregular` (ascii): in the middle of each
/// element one entry split over two lines and two entries on one line, which the blocks cannot take.
/// `bad_face`: that face names a vertex past the last.
std::string large_sheet(Format format, int n, bool irregular, int64_t bad_face = -1) {
  const int cells = (n - 1) * (n - 1), quads = (cells + 6) / 7;
  PlyBuilder b(format);
  b.header("comment TextureFile page.png").header(fmt::format("element vertex {}", n * n));
  b.header("property float x").header("property float y").header("property float z");
  b.header(fmt::format("element face {}", quads + 2 * (cells - quads)));
  b.header("property list uchar int vertex_indices").header("property list uchar float texcoord");
  // A float32 value: in text the double's digits (a float's shortest digits read as a double are not
  // always the float's value).
  auto put_float = [&](double x) -> PlyBuilder& { return format == Format::kAscii ? b.put(x) : b.put(float(x)); };
  const int middle = n * n / 2;
  for (int v = 0; v < n * n; ++v) {
    put_float((v % n) * 0.25);
    put_float((v / n) * 0.5);
    if (irregular && v == middle) b.end();  // the vertex's z on the next line
    put_float((v % 3) * 0.125).end();
  }
  int64_t face = 0;
  auto put_face = [&](std::initializer_list<int> corners) {
    b.put(uint8_t(corners.size()));
    for (int c : corners) b.put(int32_t(face == bad_face ? n * n + 5 : c));
    if (irregular && face == cells / 2) b.end();  // the face's texture coordinates on the next line
    b.put(uint8_t(2 * corners.size()));
    for (int c : corners) put_float((c % n) / 1024.0), put_float((c / n) / 2048.0);
    b.end();
    ++face;
  };
  for (int cell = 0; cell < cells; ++cell) {
    const int i = cell % (n - 1), j = cell / (n - 1), v = j * n + i;
    if (cell % 7 == 0) {
      put_face({v, v + 1, v + n + 1, v + n});
    } else {
      put_face({v, v + 1, v + n + 1});
      put_face({v, v + n + 1, v + n});
    }
  }
  return b.str();
}

// A large ascii file reads as the same model in binary does, whether each entry is a line of its own
// (read in blocks) or split over two (read in one pass), and counts its lines either way.
TEST_F(PlyReaderTest, LargeAsciiFilesReadAsTheirBinaryTwin) {
  write_image("page.png", 4, 4);
  const int n = 200;  // 40000 vertices, 73544 faces: more than two blocks of each
  ModelReadOptions options;
  options.load_textures = false;
  ModelReadStats binary_stats, ascii_stats, irregular_stats;
  const TexturedMesh binary = read_ply(write("binary.ply", large_sheet(Format::kLittle, n, false)), options, &binary_stats);
  const TexturedMesh ascii = read_ply(write("ascii.ply", large_sheet(Format::kAscii, n, false)), options, &ascii_stats);
  const TexturedMesh irregular = read_ply(write("irregular.ply", large_sheet(Format::kAscii, n, true)), options, &irregular_stats);
  ASSERT_EQ(binary.positions.size(), size_t(n * n));
  for (const TexturedMesh* m : {&ascii, &irregular}) {
    EXPECT_EQ(m->positions, binary.positions);
    EXPECT_EQ(m->triangles, binary.triangles);
    EXPECT_EQ(m->corner_uv, binary.corner_uv);
    EXPECT_EQ(m->face_material, binary.face_material);
  }
  EXPECT_EQ(ascii_stats.polygons_triangulated, binary_stats.polygons_triangulated);
  EXPECT_EQ(irregular_stats.polygons_triangulated, binary_stats.polygons_triangulated);
  EXPECT_EQ(irregular_stats.lines, ascii_stats.lines + 2);  // one line more in the vertices, one more in the faces
}

// An entry's values end its line: a line holding more values than the header declares (two entries
// joined, or one with a value too many) is refused at that line, not where the next entry misreads.
TEST_F(PlyReaderTest, SurplusValuesOnALineAreRefusedAtThatLine) {
  std::string text = large_sheet(Format::kAscii, 20, false);
  const size_t body = text.find("end_header\n") + 11;
  size_t line = size_t(std::count(text.begin(), text.begin() + long(body), '\n')) + 1;
  size_t at = body;
  for (int i = 0; i < 400 + 5; ++i, ++line) at = text.find('\n', at) + 1;  // the sixth face's line
  text[text.find('\n', at)] = ' ';                                         // the seventh joined to it
  try {
    read_ply(write("joined.ply", text), ModelReadOptions{false});
    ADD_FAILURE() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fmt::format("joined.ply:{}: face 5: more values on the line", line)), std::string::npos)
        << e.what();
  }
}

// Ascii files damaged at random places in their body (a byte replaced, removed or doubled; two entries
// joined on one line, an entry split over two; a digit changed) read alike in blocks of 7 and 1000
// entries and in one pass: the same mesh and stats, or the same one-line error.
// A block that meets a problem, or does not hold exactly its entries, hands the element to the one-pass
// read; nothing a block read wrongly may survive. (The fuzz corpus's files are too small for blocks.)
TEST_F(PlyReaderTest, DamagedAsciiFilesReadAlikeInBlocksAndInOnePass) {
  const std::string text = large_sheet(Format::kAscii, 60, false);  // 3600 vertices, 6620 faces
  const size_t body = text.find("end_header\n") + 11;
  const std::string alphabet = "0123456789 .-+e\n\tx";
  ModelReadOptions options;
  options.load_textures = false;
  struct Outcome {
    std::string error;
    TexturedMesh mesh;
    ModelReadStats stats;
  };
  auto read_with = [&](const std::string& path, uint64_t block_entries) {
    Outcome o;
    try {
      o.mesh = read_ply_in_blocks(path, options, &o.stats, block_entries);
    } catch (const InputError& e) {
      o.error = e.what();
    }
    return o;
  };
  std::mt19937 rng(25);
  // The first byte at or after `from` that is one of `of` (from the body's start if none is).
  auto next_of = [&](const std::string& t, size_t from, const char* of) {
    const size_t at = t.find_first_of(of, from);
    return at == std::string::npos ? t.find_first_of(of, body) : at;
  };
  int refused = 0;
  for (int trial = 0; trial < 120; ++trial) {
    std::string damaged = text;
    size_t at = body + rng() % (damaged.size() - body);
    switch (trial % 6) {
      case 0:
        damaged[at] = alphabet[rng() % alphabet.size()];
        break;
      case 1:
        damaged.erase(at, 1);
        break;
      case 2:
        damaged.insert(at, 1, damaged[at]);
        break;
      case 3:
        damaged[at = next_of(damaged, at, "\n")] = ' ';
        break;  // two entries on one line
      case 4:
        damaged[at = next_of(damaged, at, " ")] = '\n';
        break;  // an entry over two lines
      case 5:
        damaged[at = next_of(damaged, at, "123456789")] = '0';
        break;  // other values, still read
    }
    const std::string path = write("damaged.ply", damaged);
    const Outcome one_pass = read_with(path, UINT64_MAX);
    refused += !one_pass.error.empty();
    EXPECT_EQ(one_pass.error.find('\n'), std::string::npos) << one_pass.error;
    for (const uint64_t block_entries : {uint64_t(7), uint64_t(1000)}) {
      const Outcome blocks = read_with(path, block_entries);
      const std::string what = fmt::format("trial {} (byte {}), blocks of {}", trial, at, block_entries);
      EXPECT_EQ(blocks.error, one_pass.error) << what;
      EXPECT_EQ(blocks.mesh.positions, one_pass.mesh.positions) << what;
      EXPECT_EQ(blocks.mesh.triangles, one_pass.mesh.triangles) << what;
      EXPECT_EQ(blocks.mesh.corner_uv, one_pass.mesh.corner_uv) << what;
      EXPECT_EQ(blocks.mesh.face_material, one_pass.mesh.face_material) << what;
      EXPECT_EQ(blocks.stats.lines, one_pass.stats.lines) << what;
      EXPECT_EQ(blocks.stats.polygons_triangulated, one_pass.stats.polygons_triangulated) << what;
    }
  }
  // Both outcomes occur: damage that still reads (a digit for a digit) and damage that is refused.
  EXPECT_GT(refused, 10);
  EXPECT_LT(refused, 100);
}

// An error deep in a large ascii file names its line, as in a small one.
TEST_F(PlyReaderTest, AnErrorDeepInALargeAsciiFileNamesItsLine) {
  const int n = 200;
  const int64_t bad = 50001;
  const std::string text = large_sheet(Format::kAscii, n, false, bad);
  const size_t header_lines = size_t(std::count(text.begin(), text.begin() + std::ptrdiff_t(text.find("end_header\n")), '\n')) + 1;
  const std::string path = write("bad.ply", text);
  EXPECT_EQ(error_of(path), fmt::format("{}:{}: face {}: vertex index {} out of range (the file has {} vertices)", path,
                                        header_lines + size_t(n * n) + size_t(bad) + 1, bad, n * n + 5, n * n));
}

// ---- end to end: a catalogue mesh written as PLY ----

/// Writes `m` as a binary little-endian PLY with per-face texcoords (float32), positions as doubles
/// (bit-exact), and its textures as PNG files beside it.
void write_ply(const TexturedMesh& m, const fs::path& path) {
  PlyBuilder b(Format::kLittle);
  for (size_t i = 0; i < m.textures.size(); ++i) {
    save_image((path.parent_path() / fmt::format("tex_{}.png", i)).string(), m.textures[i].image, ImageFormat::kPng);
    b.header(fmt::format("comment TextureFile tex_{}.png", i));
  }
  b.header(fmt::format("element vertex {}", m.positions.size()))
      .header("property double x")
      .header("property double y")
      .header("property double z")
      .header(fmt::format("element face {}", m.triangles.size()))
      .header("property list uchar int vertex_indices")
      .header("property list uchar float texcoord")
      .header("property uint8 texnumber");
  for (const Vec3& p : m.positions) b.put(p.x()).put(p.y()).put(p.z());
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    b.put(uint8_t(3)).put(int32_t(m.triangles[t][0])).put(int32_t(m.triangles[t][1])).put(int32_t(m.triangles[t][2]));
    b.put(uint8_t(6));
    for (int k = 0; k < 3; ++k) b.put(float(m.corner_uv[3 * t + k].x())).put(float(m.corner_uv[3 * t + k].y()));
    b.put(uint8_t(m.materials[size_t(m.face_material[t])].texture));
  }
  std::ofstream(path, std::ios::binary) << b.str();
}

TEST_F(PlyReaderTest, CatalogueMeshAsPlyOptimizesCleanly) {
  const TexturedMesh original = cat::multi_component();
  const fs::path ply = dir_ / "multi.ply";
  write_ply(original, ply);
  const TexturedMesh in = read_ply(ply.string());
  ASSERT_EQ(in.positions, original.positions);
  ASSERT_EQ(in.triangles, original.triangles);
  Options options;
  options.size = 128;
  const Result r = optimize(in, options);
  const auto& metrics = report_json(r.report)["metrics"];
  EXPECT_EQ(metrics["lost_triangles"].get<size_t>(), 0u);
  EXPECT_EQ(metrics["flipped"].get<size_t>(), 0u);
  EXPECT_EQ(metrics["charts"].get<size_t>(), report_json(r.report)["preparation"]["components"].get<size_t>());

  // The command line reads it too, and measures it against its output.
  const fs::path out = dir_ / "out";
  const std::string cmd = std::string(TIGHTEX_CLI) + " '" + ply.string() + "' -o '" + out.string() + "' --size 128 --quiet";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 0);
  const Metrics m = measure(in, read_ply((out / "multi.ply").string()), 20000);  // a PLY in gives a PLY out
  EXPECT_EQ(m.lost_triangles, 0u);
  EXPECT_EQ(m.flipped, 0u);
  EXPECT_EQ(m.charts, report_json(r.report)["preparation"]["components"].get<size_t>());
}

}  // namespace
}  // namespace tightex
