// Tests for the OBJ + MTL reader: small files written on the fly for every supported form and every
// refused one (checking that the message names file and line), plus the Meshroom scan from
// ../shared/data.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <string>

#include "core/error.hpp"
#include "io/image_io.hpp"
#include "io/obj_reader.hpp"
#include "io/obj_writer.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;

/// A fresh folder per test, removed afterwards.
class ObjReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / (std::string("tightex_obj_reader_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  /// Writes `text` verbatim (binary mode, so "\r\n" stays) and returns the path.
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    fs::create_directories(p.parent_path());
    std::ofstream out(p, std::ios::binary);
    out << text;
    return p.string();
  }

  /// read_obj, checked against the same file parsed with every line a stretch of its own: the mesh,
  /// the stats and the error must not depend on how the file is cut.
  static TexturedMesh read(const std::string& path, const ModelReadOptions& options = {}, ModelReadStats* stats = nullptr) {
    ModelReadStats by_line_stats;
    TexturedMesh by_line;
    std::string by_line_error;
    try {
      by_line = read_obj_in_chunks(path, options, &by_line_stats, 1);
    } catch (const InputError& e) {
      by_line_error = e.what();
    }
    try {
      TexturedMesh mesh = read_obj(path, options, stats);
      EXPECT_EQ(by_line_error, "");
      expect_same(mesh, by_line);
      if (stats != nullptr) expect_same(*stats, by_line_stats);
      return mesh;
    } catch (const InputError& e) {
      EXPECT_EQ(by_line_error, e.what());
      throw;
    }
  }

  static void expect_same(const TexturedMesh& a, const TexturedMesh& b) {
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.triangles, b.triangles);
    EXPECT_EQ(a.corner_uv, b.corner_uv);
    EXPECT_EQ(a.corner_normal, b.corner_normal);
    EXPECT_EQ(a.corner_color, b.corner_color);
    EXPECT_EQ(a.face_material, b.face_material);
    ASSERT_EQ(a.materials.size(), b.materials.size());
    for (size_t m = 0; m < a.materials.size(); ++m) {
      EXPECT_EQ(a.materials[m].name, b.materials[m].name);
      EXPECT_EQ(a.materials[m].kd, b.materials[m].kd);
      EXPECT_EQ(a.materials[m].texture, b.materials[m].texture);
      EXPECT_EQ(a.materials[m].maps, b.materials[m].maps);
      EXPECT_EQ(a.materials[m].uv_scale, b.materials[m].uv_scale);
    }
    ASSERT_EQ(a.textures.size(), b.textures.size());
    for (size_t t = 0; t < a.textures.size(); ++t) EXPECT_EQ(a.textures[t].path, b.textures[t].path);
  }

  static void expect_same(const ModelReadStats& a, const ModelReadStats& b) {
    EXPECT_EQ(a.polygons_triangulated, b.polygons_triangulated);
    EXPECT_EQ(a.lines, b.lines);
    EXPECT_EQ(a.paths_found, b.paths_found);
    EXPECT_EQ(a.not_read, b.not_read);
  }

  /// The message read_obj throws, or "" when it succeeds. Every message must be a single line.
  static std::string error_of(const std::string& path, const ModelReadOptions& options = {}) {
    try {
      read(path, options);
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
      return message;
    }
    return "";
  }

  static ModelReadOptions no_textures() {
    ModelReadOptions o;
    o.load_textures = false;
    return o;
  }

  fs::path dir_;
};

// A unit square as a quad, with its texture coordinates.
const char* const kSquareVerts =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";

TEST_F(ObjReaderTest, QuadIsFanTriangulated) {
  const std::string path = write("quad.obj", std::string(kSquareVerts) + "f 1/1 2/2 3/3 4/4\n");
  ModelReadStats stats;
  const TexturedMesh mesh = read(path, {}, &stats);
  EXPECT_EQ(mesh.source, path);
  ASSERT_EQ(mesh.num_vertices(), 4u);
  ASSERT_EQ(mesh.num_triangles(), 2u);
  EXPECT_EQ(mesh.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(mesh.triangles[1], (Tri{0, 2, 3}));
  ASSERT_EQ(mesh.corner_uv.size(), 6u);
  EXPECT_EQ(mesh.corner_uv[4], Vec2(1, 1));
  EXPECT_EQ(mesh.corner_uv[5], Vec2(0, 1));
  EXPECT_TRUE(mesh.corner_normal.empty());
  EXPECT_EQ(mesh.face_material, (std::vector<int32_t>{-1, -1}));
  EXPECT_TRUE(mesh.materials.empty());
  EXPECT_EQ(stats.polygons_triangulated, 1u);
  EXPECT_EQ(stats.lines, 9u);
}

TEST_F(ObjReaderTest, NegativeIndicesAreRelativeToTheirLine) {
  const std::string path = write("neg.obj",
                                 "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                 "f -3/-3 -2/-2 -1/-1\n"
                                 "v 5 5 5\nvt 0.5 0.5\n"
                                 "f -4/-1 -3/-3 -1/-2\n");
  const TexturedMesh mesh = read(path);
  ASSERT_EQ(mesh.num_triangles(), 2u);
  EXPECT_EQ(mesh.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(mesh.triangles[1], (Tri{0, 1, 3}));
  EXPECT_EQ(mesh.corner_uv[3], Vec2(0.5, 0.5));
  EXPECT_EQ(mesh.corner_uv[4], Vec2(1, 0));
  EXPECT_EQ(mesh.corner_uv[5], Vec2(0, 1));
}

TEST_F(ObjReaderTest, NegativeIndexBeforeDefinitionIsRefused) {
  const std::string path = write("neg_bad.obj", "v 0 0 0\nvt 0 0\nf -1/1 -2/1 -3/1\nv 1 0 0\nv 0 1 0\n");
  EXPECT_EQ(error_of(path), path + ":3: vertex index -2 out of range (only 1 vertices defined before this line)");
}

TEST_F(ObjReaderTest, CrlfTabsBlankLinesAndComments) {
  const std::string path = write("crlf.obj",
                                 "# exported on Windows\r\n"
                                 "\r\n"
                                 "o thing\r\n"
                                 "v\t0 0 0 \r\n"
                                 "v 1\t0 0\t\r\n"
                                 "v 0 1 0   # trailing comment\r\n"
                                 "   \t \r\n"
                                 "vt 0 0\r\nvt 1 0\r\nvt 0 1\r\n"
                                 "g group one\r\ns 1\r\n"
                                 "f 1/1 2/2 3/3\t\r\n"
                                 "l 1 2\r\np 1\r\n"
                                 "f 1/1 2/2 3/3");  // last line without a newline
  ModelReadStats stats;
  const TexturedMesh mesh = read(path, {}, &stats);
  ASSERT_EQ(mesh.num_triangles(), 2u);
  EXPECT_EQ(mesh.positions[1], Vec3(1, 0, 0));
  EXPECT_EQ(mesh.corner_uv[2], Vec2(0, 1));
  EXPECT_EQ(stats.lines, 16u);
}

TEST_F(ObjReaderTest, CornerFormsAndNormals) {
  const std::string path = write("normals.obj", std::string(kSquareVerts) +
                                                    "vn 0 0 1\n"
                                                    "f 1/1/1 2/2/1 3/3/1\n"
                                                    "f 1/1/-1 3/3/-1 4/4/1\n");
  const TexturedMesh mesh = read(path);
  ASSERT_EQ(mesh.corner_normal.size(), 6u);
  for (const Vec3& n : mesh.corner_normal) EXPECT_EQ(n, Vec3(0, 0, 1));
}

TEST_F(ObjReaderTest, NormalsOnSomeFacesOnlyAreDropped) {
  const std::string path = write("some_normals.obj", std::string(kSquareVerts) + "vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1 3/3 4/4\n");
  const TexturedMesh mesh = read(path);
  EXPECT_EQ(mesh.num_triangles(), 2u);
  EXPECT_TRUE(mesh.corner_normal.empty());
}

TEST_F(ObjReaderTest, VertexSlashSlashNormalHasNoTextureCoordinates) {
  const std::string path = write("vvn.obj", std::string(kSquareVerts) +
                                                "vn 0 0 1\n"
                                                "f 1/1/1 2/2/1 3/3/1\n"
                                                "f 1//1 3//1 4//1\n");
  EXPECT_EQ(error_of(path), path + ":11: face has no texture coordinates (every face needs v/vt indices)");
}

TEST_F(ObjReaderTest, FaceWithoutAnyTextureCoordinatesNamesItsLine) {
  const std::string path = write("partial_vt.obj", std::string(kSquareVerts) + "f 1/1 2/2 3/3\nf 1 3 4\n");
  EXPECT_EQ(error_of(path), path + ":10: face has no texture coordinates (every face needs v/vt indices)");
}

TEST_F(ObjReaderTest, ModelWithoutTextureCoordinates) {
  const std::string path = write("no_vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
  EXPECT_EQ(error_of(path),
            path +
                ": model has neither texture coordinates (vt) nor vertex colours (v x y z r g b); tightex needs the input's UV atlas or "
                "its vertex colours");
}

TEST_F(ObjReaderTest, ForwardReferencesAreResolvedAtTheEnd) {
  const std::string path = write("forward.obj", "f 1/1 2/2 3/3\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n");
  const TexturedMesh mesh = read(path);
  EXPECT_EQ(mesh.num_triangles(), 1u);
  EXPECT_EQ(mesh.corner_uv[1], Vec2(1, 0));
}

TEST_F(ObjReaderTest, IndexOutOfRangeNamesTheLine) {
  const std::string path = write("range.obj", std::string(kSquareVerts) + "f 1/1 2/2 3/3\n\nf 1/1 2/2 99999/3\n");
  EXPECT_EQ(error_of(path), path + ":11: vertex index 99999 out of range (file has 4 vertices)");
  const std::string vt_path = write("range_vt.obj", std::string(kSquareVerts) + "f 1/1 2/2 3/7\n");
  EXPECT_EQ(error_of(vt_path), vt_path + ":9: texture coordinate index 7 out of range (file has 4 texture coordinates)");
}

TEST_F(ObjReaderTest, ZeroIndexIsRefused) {
  const std::string path = write("zero.obj", std::string(kSquareVerts) + "f 0/1 2/2 3/3\n");
  EXPECT_EQ(error_of(path), path + ":9: index 0 is invalid (OBJ indices start at 1)");
}

TEST_F(ObjReaderTest, NonFiniteCoordinatesAreRefused) {
  const std::string nan_path = write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n");
  EXPECT_EQ(error_of(nan_path), nan_path + ":2: NaN or infinite coordinate");
  const std::string inf_path = write("inf.obj", "v 0 0 0\nv 1 0 1e999\n");
  EXPECT_EQ(error_of(inf_path), inf_path + ":2: NaN or infinite coordinate");
  const std::string vt_path = write("nan_vt.obj", "v 0 0 0\nvt 0 -inf\n");
  EXPECT_EQ(error_of(vt_path), vt_path + ":2: NaN or infinite texture coordinate");
  const std::string absurd = write("absurd.obj", "v 0 0 0\nv 0 2e15 0\n");
  EXPECT_EQ(error_of(absurd), absurd + ":2: absurd coordinate 2e+15 (absolute value above 1e15)");
}

TEST_F(ObjReaderTest, MalformedNumbersAreRefused) {
  const std::string path = write("bad_number.obj", "v 0 0 0\nv 1 abc 0\n");
  EXPECT_EQ(error_of(path), path + ":2: malformed number 'abc' in 'v'");
  const std::string glued = write("glued.obj", "vt 0.5x 0\n");
  EXPECT_EQ(error_of(glued), glued + ":1: malformed number '0.5x' in 'vt'");
  const std::string few = write("few.obj", "v 1 2\n");
  EXPECT_EQ(error_of(few), few + ":1: 'v' needs 3 coordinates, got 2");
  const std::string corner = write("bad_corner.obj", std::string(kSquareVerts) + "f 1/1 2/x 3/3\n");
  EXPECT_EQ(error_of(corner), corner + ":9: malformed face corner '2/x'");
}

TEST_F(ObjReaderTest, VertexColoursAndPlusSignsAreAccepted) {
  const std::string path = write("colours.obj",
                                 "v 0 0 0 1 0.5 0.25\nv +1 0 0 0 0 0\nv 0 1 0 1.0\n"
                                 "vt 0 0 0\nvt 1\nvt 0 1\nf 1/1 2/2 3/3\n");
  const TexturedMesh mesh = read(path);
  EXPECT_EQ(mesh.positions[1], Vec3(1, 0, 0));
  EXPECT_EQ(mesh.corner_uv[1], Vec2(1, 0));
}

TEST_F(ObjReaderTest, FaceWithTwoCornersIsRefused) {
  const std::string path = write("two.obj", std::string(kSquareVerts) + "f 1/1 2/2\n");
  EXPECT_EQ(error_of(path), path + ":9: face has 2 corners (needs at least 3)");
}

TEST_F(ObjReaderTest, UnknownStatementsAreIgnored) {
  const std::string path = write("unknown.obj", std::string(kSquareVerts) + "vp 0.5\ncstype bspline\nmg 1\nf 1/1 2/2 3/3\n");
  EXPECT_EQ(read(path).num_triangles(), 1u);
}

TEST_F(ObjReaderTest, EmptyAndUnreadableFiles) {
  const std::string empty = write("empty.obj", "");
  EXPECT_EQ(error_of(empty), empty + ": no faces");
  const std::string only_verts = write("verts.obj", kSquareVerts);
  EXPECT_EQ(error_of(only_verts), only_verts + ": no faces");
  EXPECT_EQ(error_of(dir_.string()), dir_.string() + ": is a directory, not a file");
  const std::string missing = (dir_ / "missing.obj").string();
  EXPECT_EQ(error_of(missing), missing + ": not found");
  const std::string binary = write("binary.obj", std::string("\x89PNG\r\n\x1a\n\0\0\0", 11));
  EXPECT_NE(error_of(binary).find("not a text file"), std::string::npos);
}

TEST_F(ObjReaderTest, MaterialsAndFacesBeforeUsemtl) {
  write("mats.mtl",
        "# comment\n"
        "newmtl red\nKa 1 1 1\nKd 1 0 0\nillum 2\n\n"
        "newmtl grey\nKd 0.5\n"
        "newmtl unused\nKd 0 0 1\n");
  const std::string path = write("mats.obj", std::string("mtllib mats.mtl\n") + kSquareVerts +
                                                 "f 1/1 2/2 3/3\n"
                                                 "usemtl grey\nf 1/1 3/3 4/4\n"
                                                 "usemtl red\nf 1/1 2/2 4/4\n"
                                                 "usemtl grey\nf 2/2 3/3 4/4\n");
  const TexturedMesh mesh = read(path);
  // Materials in order of first use; unused ones are left out.
  ASSERT_EQ(mesh.materials.size(), 2u);
  EXPECT_EQ(mesh.materials[0].name, "grey");
  EXPECT_EQ(mesh.materials[0].kd, (std::array<double, 3>{0.5, 0.5, 0.5}));
  EXPECT_EQ(mesh.materials[1].name, "red");
  EXPECT_EQ(mesh.materials[1].kd, (std::array<double, 3>{1, 0, 0}));
  EXPECT_EQ(mesh.materials[1].texture, -1);
  EXPECT_EQ(mesh.face_material, (std::vector<int32_t>{-1, 0, 1, 0}));
  EXPECT_TRUE(mesh.textures.empty());
}

TEST_F(ObjReaderTest, MissingMaterialLibrary) {
  const std::string path = write("no_mtl.obj", std::string(kSquareVerts) + "mtllib nowhere.mtl\nf 1/1 2/2 3/3\n");
  EXPECT_EQ(error_of(path), path + ":9: material library 'nowhere.mtl' not found");
  const std::string spaced = write("no_mtl2.obj", "mtllib my materials.mtl\n");
  EXPECT_EQ(error_of(spaced), spaced + ":1: material library 'my materials.mtl' not found");
}

TEST_F(ObjReaderTest, SeveralLibrariesAndNamesWithSpaces) {
  write("a.mtl", "newmtl first\nKd 1 0 0\n");
  write("b.mtl", "newmtl second\nKd 0 1 0\n");
  write("sub dir/my mats.mtl", "newmtl third\nKd 0 0 1\n");
  const std::string path = write("multi.obj", std::string("mtllib a.mtl b.mtl\nmtllib sub dir\\my mats.mtl\n") + kSquareVerts +
                                                  "usemtl third\nf 1/1 2/2 3/3\nusemtl second\nf 1/1 3/3 4/4\n");
  const TexturedMesh mesh = read(path);
  ASSERT_EQ(mesh.materials.size(), 2u);
  EXPECT_EQ(mesh.materials[0].name, "third");
  EXPECT_EQ(mesh.materials[1].name, "second");

  const std::string half = write("half.obj", "mtllib a.mtl c.mtl\n");
  EXPECT_EQ(error_of(half), half + ":1: material library 'c.mtl' not found");
}

TEST_F(ObjReaderTest, UsemtlOfUndefinedMaterial) {
  write("m.mtl", "newmtl known\nKd 1 1 1\n");
  const std::string path =
      write("undef.obj", std::string("mtllib m.mtl\n") + kSquareVerts + "usemtl known\nf 1/1 2/2 3/3\nusemtl mystery\nf 1/1 3/3 4/4\n");
  EXPECT_EQ(error_of(path), path + ":12: material 'mystery' is not defined in any material library");
  const std::string no_lib = write("no_lib.obj", std::string(kSquareVerts) + "usemtl known\nf 1/1 2/2 3/3\n");
  EXPECT_EQ(error_of(no_lib), no_lib + ":9: material 'known' used but the file names no material library (mtllib)");
}

TEST_F(ObjReaderTest, UsemtlBeforeMtllibIsResolved) {
  write("late.mtl", "newmtl late\nKd 0 0 0\n");
  const std::string path = write("late.obj", std::string(kSquareVerts) + "usemtl late\nf 1/1 2/2 3/3\nmtllib late.mtl\n");
  const TexturedMesh mesh = read(path);
  ASSERT_EQ(mesh.materials.size(), 1u);
  EXPECT_EQ(mesh.face_material[0], 0);
}

TEST_F(ObjReaderTest, MapKdOptionsAndFileNameWithSpaces) {
  write("tex.mtl",
        "newmtl tiled\r\n"
        "Kd 1 1 1\r\n"
        "map_Kd -blendu on -blendv off -bm 1 -boost 2 -clamp off -s 2 3 1 -o 0.25 0.5 -mm 0 1 "
        "-t 0 0 0 -texres 512 -imfchan r -cc off textures\\my texture.png\r\n"
        "newmtl same_texture\n"
        "map_kd textures/my texture.png\n"
        "newmtl short_options\n"
        "map_Kd -s 4 other.png\n");
  const std::string path = write("tex.obj", std::string("mtllib tex.mtl\n") + kSquareVerts +
                                                "usemtl tiled\nf 1/1 2/2 3/3\n"
                                                "usemtl same_texture\nf 1/1 3/3 4/4\n"
                                                "usemtl short_options\nf 2/2 3/3 4/4\n");
  const TexturedMesh mesh = read(path, no_textures());
  ASSERT_EQ(mesh.materials.size(), 3u);
  const Material& tiled = mesh.materials[0];
  EXPECT_EQ(tiled.uv_scale, (std::array<double, 2>{2, 3}));
  EXPECT_EQ(tiled.uv_offset, (std::array<double, 2>{0.25, 0.5}));
  // Both materials name the same file: one texture.
  ASSERT_EQ(mesh.textures.size(), 2u);
  EXPECT_EQ(tiled.texture, 0);
  EXPECT_EQ(mesh.materials[1].texture, 0);
  EXPECT_EQ(mesh.materials[2].texture, 1);
  EXPECT_EQ(fs::path(mesh.textures[0].path), (dir_ / "textures/my texture.png").lexically_normal());
  EXPECT_TRUE(mesh.textures[0].image.empty());  // not loaded
  // -s with only u leaves v at 1.
  EXPECT_EQ(mesh.materials[2].uv_scale, (std::array<double, 2>{4, 1}));
  // The sampled coordinate applies the transform.
  EXPECT_EQ(mesh.sampled_uv(0, 1), Vec2(2 * 1 + 0.25, 3 * 0 + 0.5));
}

TEST_F(ObjReaderTest, TexturesAreLoaded) {
  Image image(2, 3, Rgba8{10, 20, 30, 255});
  fs::create_directories(dir_ / "textures");
  save_image((dir_ / "textures/atlas page.png").string(), image, ImageFormat::kPng);
  write("t.mtl", "newmtl a\nmap_Kd -s 1 1 textures/atlas page.png\nnewmtl b\nmap_Kd textures/atlas page.png\n");
  const std::string path =
      write("t.obj", std::string("mtllib t.mtl\n") + kSquareVerts + "usemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 1/1 3/3 4/4\n");
  const TexturedMesh mesh = read(path);
  ASSERT_EQ(mesh.textures.size(), 1u);
  EXPECT_EQ(mesh.textures[0].image.width, 2);
  EXPECT_EQ(mesh.textures[0].image.height, 3);
  EXPECT_EQ(mesh.materials[0].texture, 0);
  EXPECT_EQ(mesh.materials[1].texture, 0);
  // Read without pixels, then decoded: the same texture, pixel for pixel; the model read is untouched.
  const TexturedMesh geometry = read(path, no_textures());
  const std::vector<Texture> decoded = load_texture_pixels(geometry);
  ASSERT_EQ(decoded.size(), 1u);
  EXPECT_EQ(decoded[0].path, mesh.textures[0].path);
  EXPECT_EQ(decoded[0].image.pixels, image.pixels);
  EXPECT_TRUE(geometry.textures[0].image.empty());
}

// Files named as another machine saw them: a Windows exporter's absolute path in quotes, a name whose
// case differs from the file's (case-insensitive file systems), an MTL library in other case. Each is
// found under the model's folder, and the report lists how (ModelReadStats::paths_found).
TEST_F(ObjReaderTest, FilesNamedByAnotherMachineAreFound) {
  fs::create_directories(dir_ / "Textures");
  save_image((dir_ / "Textures/Tex_0.PNG").string(), Image(4, 2, Rgba8{10, 20, 30, 255}), ImageFormat::kPng);
  save_image((dir_ / "tex_1.png").string(), Image(3, 3, Rgba8{1, 2, 3, 255}), ImageFormat::kPng);
  write("Scan.MTL",
        "newmtl a\nmap_Kd \"C:\\Users\\me\\scan\\textures\\tex_0.png\"\n"
        "newmtl b\nmap_Kd TEX_1.PNG\n");
  const std::string path =
      write("scan.obj", std::string("mtllib scan.mtl\n") + kSquareVerts + "usemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 1/1 3/3 4/4\n");
  ModelReadStats stats;
  const TexturedMesh mesh = read(path, {}, &stats);
  ASSERT_EQ(mesh.textures.size(), 2u);
  EXPECT_EQ(mesh.textures[0].image.width, 4);
  EXPECT_EQ(fs::path(mesh.textures[0].path), dir_ / "Textures/Tex_0.PNG");
  EXPECT_EQ(mesh.textures[1].image.width, 3);
  ASSERT_EQ(stats.paths_found.size(), 3u);
  EXPECT_EQ(stats.paths_found[0], "scan.mtl -> " + (dir_ / "Scan.MTL").string());
  EXPECT_EQ(stats.paths_found[1], "\"C:/Users/me/scan/textures/tex_0.png\" -> " + (dir_ / "Textures/Tex_0.PNG").string());
}

// Two files whose names differ only in case: the exact name wins; a third spelling matches neither
// (ambiguous) and is reported missing, as is a path none of whose tails exists.
TEST_F(ObjReaderTest, AmbiguousOrAbsentNamesAreNotGuessed) {
  save_image((dir_ / "t.png").string(), Image(2, 2), ImageFormat::kPng);
  save_image((dir_ / "T.png").string(), Image(5, 5), ImageFormat::kPng);
  write("m.mtl", "newmtl a\nmap_Kd T.png\nnewmtl b\nmap_Kd t.PNG\nnewmtl c\nmap_Kd C:/elsewhere/none.png\n");
  auto model = [&](const char* material) {
    return write(std::string(material) + ".obj", std::string("mtllib m.mtl\n") + kSquareVerts + "usemtl " + material + "\nf 1/1 2/2 3/3\n");
  };
  EXPECT_EQ(read(model("a")).textures.at(0).image.width, 5);
  EXPECT_NE(error_of(model("b")).find("texture 't.PNG' of material 'b' could not be loaded"), std::string::npos);
  EXPECT_NE(error_of(model("c")).find("texture 'C:/elsewhere/none.png' of material 'c' could not be loaded"), std::string::npos);
}

TEST_F(ObjReaderTest, MissingTextureNamesTheMaterialLibraryLine) {
  const std::string mtl = write("gone.mtl", "newmtl a\nKd 1 1 1\nmap_Kd gone.png\n");
  const std::string path = write("gone.obj", std::string("mtllib gone.mtl\n") + kSquareVerts + "usemtl a\nf 1/1 2/2 3/3\n");
  const std::string message = error_of(path);
  EXPECT_EQ(message.rfind(mtl + ":3: texture 'gone.png' of material 'a' could not be loaded: ", 0), 0u) << message;
  // Without pixels the path is kept and nothing is opened; decoding it later names the same line.
  const TexturedMesh mesh = read(path, no_textures());
  ASSERT_EQ(mesh.textures.size(), 1u);
  EXPECT_EQ(fs::path(mesh.textures[0].path), dir_ / "gone.png");
  try {
    load_texture_pixels(mesh);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST_F(ObjReaderTest, MalformedMaterialLibrary) {
  const std::string mtl = write("bad.mtl", "newmtl a\nKd 1 x 1\n");
  const std::string path = write("bad.obj", std::string("mtllib bad.mtl\n") + kSquareVerts + "f 1/1 2/2 3/3\n");
  EXPECT_EQ(error_of(path), mtl + ":2: malformed number 'x' in 'Kd'");
  const std::string opt = write("opt.mtl", "newmtl a\nmap_Kd -zoom 2 tex.png\n");
  const std::string opt_obj = write("opt.obj", std::string("mtllib opt.mtl\n") + kSquareVerts + "f 1/1 2/2 3/3\n");
  EXPECT_EQ(error_of(opt_obj), opt + ":2: unknown option '-zoom' in 'map_Kd'");
}

TEST_F(ObjReaderTest, DevicesAndPipesNamedByTheModelAreRefused) {
  // A model naming /dev/zero as its library or texture would be read until memory ran out, and a FIFO
  // with no writer would block forever; only regular files are read on a model's say-so.
  // /dev/zero lies outside the model's folder: read only with allow_outside_files.
  ASSERT_EQ(::mkfifo((dir_ / "pipe").c_str(), 0600), 0);
  ModelReadOptions outside;
  outside.allow_outside_files = true;
  for (const std::string special : {"/dev/zero", "pipe"}) {
    const std::string lib = write("lib.obj", "mtllib " + special + "\n" + kSquareVerts + "f 1/1 2/2 3/3\n");
    EXPECT_EQ(error_of(lib, outside), lib + ":1: material library '" + special + "' is not a regular file (a device, pipe or socket)");
    const std::string mtl = write("tex.mtl", "newmtl a\nmap_Kd " + special + "\n");
    const std::string tex = write("tex.obj", std::string("mtllib tex.mtl\nusemtl a\n") + kSquareVerts + "f 1/1 2/2 3/3\n");
    const std::string message = error_of(tex, outside);
    EXPECT_EQ(message.rfind(mtl + ":2: texture '" + special + "' of material 'a' could not be loaded: ", 0), 0u) << message;
    EXPECT_NE(message.find("is not a regular file"), std::string::npos) << message;
    if (special[0] == '/') {
      EXPECT_EQ(error_of(lib).rfind(lib + ":1: material library '/dev/zero' is an absolute path out of the folder ", 0), 0u)
          << error_of(lib);
      EXPECT_EQ(error_of(tex).rfind(mtl + ":2: map_Kd '/dev/zero' is an absolute path out of the folder ", 0), 0u) << error_of(tex);
    } else {
      EXPECT_EQ(error_of(lib), error_of(lib, outside));
    }
  }
}

TEST_F(ObjReaderTest, TheFirstProblemInFileOrderIsReportedHoweverTheFileIsCut) {
  // read() parses each file also with every line a stretch of its own; what depends on the lines
  // before (colours are all-or-nothing, libraries are read as their line comes) must come out the same.
  const std::string verts = "vt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";
  const std::string uncoloured_first = write("a.obj", "v 0 0 0 1 1 1\nv 1 0 0\nv 0 1 0 -1 0 0\n" + verts);
  const TexturedMesh mesh = read(uncoloured_first);
  EXPECT_TRUE(mesh.corner_color.empty());  // the bad colour after an uncoloured vertex is not read at all
  const std::string coloured_first = write("b.obj", "v 0 0 0 1 1 1\nv 1 0 0 1 1 1\nv 0 1 0 -1 0 0\n" + verts);
  EXPECT_EQ(error_of(coloured_first), coloured_first + ":3: vertex colour -1 is not a number from 0 to 1 (or 0 to 255)");
  const std::string library_first = write("c.obj", "mtllib nowhere.mtl\nv 0 0\n" + verts);
  EXPECT_EQ(error_of(library_first), library_first + ":1: material library 'nowhere.mtl' not found");
  const std::string vertex_first = write("d.obj", "v 0 0\nmtllib nowhere.mtl\n" + verts);
  EXPECT_EQ(error_of(vertex_first), vertex_first + ":1: 'v' needs 3 coordinates, got 2");
  const std::string relative = write("e.obj", "v 0 0 0\nv 1 0 0\nvt 0 0\nv 0 1 0\nvt 1 0\nvt 0 1\nf -3/-3 -2/-2 -1/-1\nf -4/1 1/1 2/2\n");
  EXPECT_EQ(error_of(relative), relative + ":8: vertex index -4 out of range (only 3 vertices defined before this line)");
}

// The writer formats its lines in blocks on every core: the file it writes must still read back corner
// for corner, with each distinct texture coordinate and normal written once, in order of first use, and
// a usemtl line wherever the material changes. Three blocks of triangles and a few hundred distinct
// coordinates, -0 among them (a coordinate of its own as text).
TEST_F(ObjReaderTest, WrittenModelReadsBackCornerForCorner) {
  constexpr uint32_t kSide = 130;  // 2 x 129^2 = 33282 triangles
  TexturedMesh mesh;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (uint32_t i = 0; i < kSide * kSide; ++i) mesh.positions.push_back(Vec3(unit(rng), unit(rng), unit(rng) * 1e-7));
  auto coordinate = [&](int steps) {
    const int k = int(rng() % uint64_t(steps));
    return k == 0 ? -0.0 : double(k) / double(steps - 1) / 3.0;
  };
  for (uint32_t y = 0; y + 1 < kSide; ++y)
    for (uint32_t x = 0; x + 1 < kSide; ++x) {
      const uint32_t v = y * kSide + x;
      for (const Tri& t : {Tri{v, v + 1, v + kSide + 1}, Tri{v, v + kSide + 1, v + kSide}}) {
        mesh.triangles.push_back(t);
        // Runs of each material, some longer than a block, and the first triangles without one.
        const size_t n = mesh.triangles.size();
        mesh.face_material.push_back(n < 5 ? -1 : int32_t((n / 20011 + n / 7 % 3) % 3));
        for (int k = 0; k < 3; ++k) {
          mesh.corner_uv.push_back(Vec2(coordinate(20), coordinate(17)));
          mesh.corner_normal.push_back(Vec3(coordinate(3), coordinate(4), 1.0));
        }
      }
    }
  for (const char* name : {"stone", "moss", "rust"}) mesh.materials.push_back(Material{name});
  write_obj(mesh, dir_.string(), "model", ImageFormat::kPng);
  const TexturedMesh back = read((dir_ / "model.obj").string(), no_textures());
  EXPECT_EQ(back.positions, mesh.positions);
  EXPECT_EQ(back.triangles, mesh.triangles);
  EXPECT_EQ(back.face_material, mesh.face_material);
  ASSERT_EQ(back.corner_uv.size(), mesh.corner_uv.size());
  ASSERT_EQ(back.corner_normal.size(), mesh.corner_normal.size());
  for (size_t c = 0; c < mesh.corner_uv.size(); ++c) {
    ASSERT_EQ(std::signbit(back.corner_uv[c].x()), std::signbit(mesh.corner_uv[c].x())) << c;
    ASSERT_EQ(back.corner_uv[c], mesh.corner_uv[c]) << c;
    ASSERT_EQ(std::signbit(back.corner_normal[c].x()), std::signbit(mesh.corner_normal[c].x())) << c;
    ASSERT_EQ(back.corner_normal[c], mesh.corner_normal[c]) << c;
  }
  // The vt and vn lines: each distinct text once, in order of first use; usemtl at every change.
  std::ifstream file(dir_ / "model.obj");
  std::vector<std::string> vt, vn;
  size_t usemtl = 0;
  for (std::string line; std::getline(file, line);) {
    if (line.rfind("vt ", 0) == 0) vt.push_back(line);
    if (line.rfind("vn ", 0) == 0) vn.push_back(line);
    usemtl += line.rfind("usemtl ", 0) == 0;
  }
  auto first_use = [](size_t n, auto line_of) {
    std::vector<std::string> lines;
    std::set<std::string> seen;
    for (size_t i = 0; i < n; ++i)
      if (seen.insert(line_of(i)).second) lines.push_back(line_of(i));
    return lines;
  };
  EXPECT_EQ(vt, first_use(mesh.corner_uv.size(), [&](size_t c) {
              return "vt " + format_double(mesh.corner_uv[c].x()) + " " + format_double(mesh.corner_uv[c].y());
            }));
  EXPECT_EQ(vn, first_use(mesh.corner_normal.size(), [&](size_t c) {
              const Vec3& n = mesh.corner_normal[c];
              return "vn " + format_double(n.x()) + " " + format_double(n.y()) + " " + format_double(n.z());
            }));
  EXPECT_GT(vt.size(), 300u);
  size_t changes = 0;
  for (size_t t = 0; t < mesh.face_material.size(); ++t)
    changes += mesh.face_material[t] >= 0 && (t == 0 || mesh.face_material[t - 1] != mesh.face_material[t]);
  EXPECT_EQ(usemtl, changes);
  EXPECT_GT(changes, 3000u);
}

TEST_F(ObjReaderTest, MeshroomScan) {
  const fs::path obj = fs::path(TIGHTEX_SHARED_DATA) / "meshroom_esp32cam" / "texturedMesh.obj";
  if (!fs::exists(obj)) GTEST_SKIP() << obj << " not present";
  ModelReadStats stats;
  const auto start = std::chrono::steady_clock::now();
  const TexturedMesh mesh = read_obj(obj.string(), no_textures(), &stats);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("read_obj(%s): %.1f ms\n", obj.filename().c_str(), ms);
  // Cut into many stretches or read as one: the same mesh.
  for (const size_t chunk_bytes : {size_t(4096), std::numeric_limits<size_t>::max()}) {
    ModelReadStats chunk_stats;
    expect_same(mesh, read_obj_in_chunks(obj.string(), no_textures(), &chunk_stats, chunk_bytes));
    expect_same(stats, chunk_stats);
  }
  EXPECT_EQ(mesh.num_triangles(), 53364u);
  EXPECT_EQ(mesh.num_vertices(), 26984u);
  EXPECT_EQ(mesh.corner_uv.size(), 3u * 53364u);
  EXPECT_TRUE(mesh.corner_normal.empty());
  ASSERT_EQ(mesh.materials.size(), 1u);
  ASSERT_EQ(mesh.textures.size(), 1u);
  EXPECT_EQ(fs::path(mesh.textures[0].path).filename(), "texture_1001.png");
  for (int32_t m : mesh.face_material) ASSERT_EQ(m, 0);
  EXPECT_EQ(stats.polygons_triangulated, 0u);
}

}  // namespace
}  // namespace tightex
