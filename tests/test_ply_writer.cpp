// Tests for the PLY writer: a catalogue mesh with two textures and a material without one, written by
// write_ply and read back by read_ply (positions bit for bit, triangles, corner UVs to float precision,
// each face's texture, the texture files), the float-or-double choice for positions, and the command
// line: a PLY in gives a PLY out by default that measures clean, and --output-format obj gives an OBJ.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "command_line.hpp"
#include "core/error.hpp"
#include "io/output_files.hpp"
#include "mesh_catalogue.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;
namespace cat = tightex::testing;

/// multi_component()'s torus: its triangles come first (32 x 16 quads, two triangles each).
constexpr size_t kTorusTriangles = 2 * 32 * 16;

/// multi_component() with two textured materials (the torus: the gradient; the disk and the floaters:
/// a checker, its coordinates moved by a -o offset) and, when `untextured_quad`, the quad floater (its
/// last two triangles) in a third material with only a Kd colour.
TexturedMesh two_texture_mesh(bool untextured_quad) {
  TexturedMesh m = cat::multi_component();
  m.textures[0].path = "tex_gradient";
  m.textures.push_back(Texture{"tex_checker", cat::checker_image(), 0, 0});
  Material checker;
  checker.name = "checker";
  checker.texture = 1;
  m.materials.push_back(checker);
  for (size_t t = kTorusTriangles; t < m.num_triangles(); ++t) m.face_material[t] = 1;
  if (untextured_quad) {
    m.materials[1].uv_offset = {0.25, 0.0};
    Material plain;
    plain.name = "plain";
    plain.kd = {0.5, 0.25, 0.125};
    m.materials.push_back(plain);
    m.face_material[m.num_triangles() - 1] = m.face_material[m.num_triangles() - 2] = 2;
  }
  return m;
}

/// The texture a face shows: its material's, or -1.
int face_texture(const TexturedMesh& m, size_t t) { return m.face_material[t] < 0 ? -1 : m.materials[size_t(m.face_material[t])].texture; }

/// The PLY header's text, up to and including end_header.
std::string header_of(const fs::path& ply) {
  std::ifstream f(ply, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(f)), {});
  return bytes.substr(0, bytes.find("end_header\n") + 11);
}

std::set<std::string> files_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

class PlyWriterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / (std::string("tightex_ply_writer_") +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST_F(PlyWriterTest, ReadsBackWhatItWrote) {
  const TexturedMesh m = two_texture_mesh(true);
  write_ply(m, dir_.string(), "multi", ImageFormat::kPng);
  EXPECT_EQ(files_in(dir_), (std::set<std::string>{"multi.ply", "tex_gradient.png", "tex_checker.png"}));  // no temporaries left
  const std::string header = header_of(dir_ / "multi.ply");
  EXPECT_EQ(header.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u) << header;
  EXPECT_NE(header.find("comment TextureFile tex_gradient.png\ncomment TextureFile tex_checker.png\n"), std::string::npos) << header;
  EXPECT_NE(header.find("property double x\n"), std::string::npos) << header;  // the torus's coordinates are not all floats
  EXPECT_NE(header.find("property list uchar int vertex_indices\nproperty list uchar float texcoord\nproperty int texnumber\n"),
            std::string::npos)
      << header;

  const TexturedMesh back = read_ply((dir_ / "multi.ply").string());
  ASSERT_EQ(back.positions.size(), m.positions.size());
  EXPECT_EQ(std::memcmp(back.positions.data(), m.positions.data(), m.positions.size() * sizeof(Vec3)), 0);  // bit for bit
  EXPECT_EQ(back.triangles, m.triangles);
  ASSERT_EQ(back.corner_uv.size(), m.corner_uv.size());
  // texcoord is float: each coordinate is the float nearest the one a renderer samples (the -o offset
  // applied), so it is within half a float ulp, 2^-25 for coordinates in [0.5, 1.5), 2^-24 below 2:
  // 2^-24 is the tolerance, far below a texel of a 65536-texel texture (2^-16).
  for (size_t t = 0; t < m.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec2 want = m.sampled_uv(t, k), got = back.corner_uv[3 * t + size_t(k)];
      for (int i = 0; i < 2; ++i) {
        EXPECT_EQ(got[i], double(float(want[i]))) << "triangle " << t << " corner " << k;
        EXPECT_LE(std::abs(got[i] - want[i]), std::ldexp(1.0, -24)) << "triangle " << t << " corner " << k;
      }
    }
  // Each face shows the same texture (the untextured quad: none), and the textures are the same pixels.
  ASSERT_EQ(back.face_material.size(), m.face_material.size());
  for (size_t t = 0; t < m.num_triangles(); ++t) {
    const int want = face_texture(m, t);
    EXPECT_EQ(back.face_material[t] < 0 ? -1 : face_texture(back, t), want) << "triangle " << t;
  }
  ASSERT_EQ(back.textures.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(fs::path(back.textures[i].path).filename(), m.textures[i].path + ".png");
    EXPECT_TRUE(back.textures[i].image.pixels == m.textures[i].image.pixels) << "texture " << i;
  }
}

TEST_F(PlyWriterTest, PositionsAreFloatWhereThatIsExact) {
  TexturedMesh m = two_texture_mesh(false);
  for (Vec3& p : m.positions) p = Vec3(float(p.x()), float(p.y()), float(p.z()));
  write_ply(m, dir_.string(), "m", ImageFormat::kJpeg);
  EXPECT_NE(header_of(dir_ / "m.ply").find("property float x\nproperty float y\nproperty float z\n"), std::string::npos);
  EXPECT_EQ(files_in(dir_), (std::set<std::string>{"m.ply", "tex_gradient.jpg", "tex_checker.jpg"}));
  const TexturedMesh back = read_ply((dir_ / "m.ply").string());
  EXPECT_EQ(std::memcmp(back.positions.data(), m.positions.data(), m.positions.size() * sizeof(Vec3)), 0);
  EXPECT_EQ(back.triangles, m.triangles);
}

TEST_F(PlyWriterTest, AFolderThatCannotBeMadeIsAnInputError) {
  std::ofstream(dir_ / "file") << "x";
  EXPECT_THROW(write_ply(two_texture_mesh(false), (dir_ / "file").string(), "m", ImageFormat::kPng), InputError);
}

/// The docs/metrics.md figures of `tightex measure IN OUT`, as JSON.
nlohmann::json measure_cli(const fs::path& in, const fs::path& out, const fs::path& json) {
  EXPECT_EQ(testing::run_tightex("measure '" + in.string() + "' '" + out.string() + "' --samples 20000 > '" + json.string() + "'"), 0);
  std::ifstream f(json);
  return nlohmann::json::parse(f);
}

TEST_F(PlyWriterTest, CommandLineWritesTheInputsKindOrTheOneAskedFor) {
  const TexturedMesh m = two_texture_mesh(false);
  write_ply(m, (dir_ / "in").string(), "multi", ImageFormat::kPng);
  const fs::path in = dir_ / "in" / "multi.ply";
  const std::string common = " --size 128 --quiet";

  // Default: a PLY in gives a PLY out, which read_ply reads and which measures clean.
  ASSERT_EQ(testing::run_tightex("'" + in.string() + "' -o '" + (dir_ / "out").string() + "'" + common), 0);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "multi.ply"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "multi.obj"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "multi.mtl"));
  const TexturedMesh out = read_ply((dir_ / "out" / "multi.ply").string());
  EXPECT_EQ(out.num_triangles(), m.num_triangles());
  const nlohmann::json metrics = measure_cli(in, dir_ / "out" / "multi.ply", dir_ / "measure.json");
  EXPECT_EQ(metrics["lost_triangles"], 0);
  EXPECT_EQ(metrics["flipped"], 0);
  EXPECT_EQ(metrics["charts"], 4);  // multi_component: a torus, a disk and two floaters
  std::ifstream report_file(dir_ / "out" / "report.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  EXPECT_EQ(report["output"]["model"], "multi.ply");
  EXPECT_EQ(report["preparation"]["components"], 4);

  // --output-format obj: an OBJ from the same PLY.
  ASSERT_EQ(testing::run_tightex("'" + in.string() + "' -o '" + (dir_ / "obj").string() + "' --output-format obj" + common), 0);
  EXPECT_FALSE(fs::exists(dir_ / "obj" / "multi.ply"));
  const Metrics obj_metrics = measure(read_ply(in.string()), read_obj((dir_ / "obj" / "multi.obj").string()), 20000);
  EXPECT_EQ(obj_metrics.lost_triangles, 0u);
  EXPECT_EQ(obj_metrics.flipped, 0u);
  EXPECT_EQ(obj_metrics.charts, 4u);
}

TEST_F(PlyWriterTest, CommandLineRefusesToWriteOverAPlyInput) {
  write_ply(two_texture_mesh(false), (dir_ / "in").string(), "multi", ImageFormat::kPng);
  const fs::path in = dir_ / "in" / "multi.ply";
  const fs::path err = dir_ / "stderr.txt";
  EXPECT_EQ(testing::run_tightex("'" + in.string() + "' -o '" + (dir_ / "in").string() + "' --size 64 --quiet 2> '" + err.string() + "'"),
            1);
  std::ifstream f(err);
  const std::string message((std::istreambuf_iterator<char>(f)), {});
  EXPECT_NE(message.find("multi.ply would replace the input"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir_ / "in" / "report.json"));
}

}  // namespace
}  // namespace tightex

namespace tightex {
namespace {

// round_uvs_as_stored: the texture coordinates a run measures are those its written file holds, so the
// report's flipped and degenerate counts are the file's (glTF stores the float of 1 - v, PLY floats).
TEST(StoredUvs, RoundedAsTheFileHoldsThem) {
  const fs::path dir = fs::temp_directory_path() / "tightex_stored_uvs";
  fs::remove_all(dir);
  fs::create_directories(dir);
  TexturedMesh mesh = cat::multi_component();
  for (Vec2& uv : mesh.corner_uv) uv = Vec2(uv.x() / 3.0 + 1e-9, uv.y() / 7.0 + 1e-9);  // values no float holds
  for (const ModelFormat format : {ModelFormat::kPly, ModelFormat::kGlb}) {
    const std::string name = std::string(to_string(format));
    if (format == ModelFormat::kPly)
      write_ply(mesh, dir.string(), name, ImageFormat::kPng);
    else
      write_gltf(mesh, dir.string(), name, ImageFormat::kPng, GltfContainer::kGlb);
    const TexturedMesh back = read_model((dir / (name + "." + name)).string());
    TexturedMesh rounded = mesh;
    round_uvs_as_stored(rounded, format);
    ASSERT_EQ(back.num_triangles(), rounded.num_triangles()) << name;
    // Each written triangle's corners, found by position, carry the rounded coordinates exactly.
    size_t compared = 0;
    for (size_t t = 0; t < back.num_triangles(); ++t)
      for (size_t s = 0; s < rounded.num_triangles(); ++s) {
        bool same = true;
        for (int k = 0; k < 3; ++k)  // glTF stores positions as floats
          same = same && (back.positions[back.triangles[t][k]] - rounded.positions[rounded.triangles[s][k]]).norm() < 1e-6;
        if (!same) continue;
        for (int k = 0; k < 3; ++k)
          EXPECT_EQ(back.corner_uv[3 * t + size_t(k)], rounded.corner_uv[3 * s + size_t(k)]) << name << " triangle " << t;
        ++compared;
        break;
      }
    EXPECT_EQ(compared, back.num_triangles()) << name;
    EXPECT_NE(rounded.corner_uv, mesh.corner_uv) << name << ": the rounding changed nothing";
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tightex
