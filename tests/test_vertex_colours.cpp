// Vertex-coloured models without a texture: the PLY (vertex and face red green blue, as uchar or
// float) and OBJ (v x y z r g b, 0..1 or 0..255) readers, the texture that texture_vertex_colours makes
// (bilinear sampling inside each triangle gives the colours' linear interpolation), and the command
// line end to end on generated and real scans made vertex-coloured by the tests' own code.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>

#include "core/error.hpp"
#include "core/image.hpp"
#include "io/obj_reader.hpp"
#include "mesh_catalogue.hpp"
#include "report/metrics.hpp"
#include "tightex/io.hpp"
#include "tightex/tightex.hpp"
#include "vertex_coloured.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;
namespace cat = tightex::testing;

class VertexColours : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / (std::string("tightex_vcol_") + ::testing::UnitTest::GetInstance()->current_test_info()->name() +
                                        "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return (dir_ / name).string();
  }
  /// The message `read` throws for the file, or "" when it reads.
  template <typename Read>
  std::string error_of(Read read, const std::string& path) {
    try {
      read(path);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

void expect_colour(const std::array<float, 4>& c, double r, double g, double b, double a = 1.0) {
  EXPECT_NEAR(c[0], r, 1e-6);
  EXPECT_NEAR(c[1], g, 1e-6);
  EXPECT_NEAR(c[2], b, 1e-6);
  EXPECT_NEAR(c[3], a, 1e-6);
}

constexpr const char* kQuadHeader = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n";

TEST_F(VertexColours, PlyVertexColoursAsUcharAndFloat) {
  const std::string uchar_ply =
      write("u.ply", std::string(kQuadHeader) +
                         "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
                         "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                         "0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 128\n0 1 0 51 102 153 255\n4 0 1 2 3\n");
  const TexturedMesh m = read_ply(uchar_ply);
  ASSERT_EQ(m.num_triangles(), 2u);  // the quad, fan-triangulated
  ASSERT_EQ(m.corner_color.size(), 6u);
  expect_colour(m.corner_color[0], 1, 0, 0);
  expect_colour(m.corner_color[2], 0, 0, 1, 128 / 255.0);
  expect_colour(m.corner_color[5], 0.2, 0.4, 0.6);
  EXPECT_TRUE(m.textures.empty());

  const std::string float_ply = write("f.ply", std::string(kQuadHeader) +
                                                   "property float diffuse_red\nproperty float diffuse_green\nproperty float diffuse_blue\n"
                                                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                                   "0 0 0 0.25 0.5 1.5\n1 0 0 0 0 0\n1 1 0 0 0 0\n0 1 0 0 0 0\n4 0 1 2 3\n");
  expect_colour(read_ply(float_ply).corner_color[0], 0.25, 0.5, 1.0);  // clamped to [0, 1]
}

TEST_F(VertexColours, PlyFaceColourWinsOverTheVertices) {
  const std::string ply = write("face.ply", std::string(kQuadHeader) +
                                                "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                                                "element face 1\nproperty list uchar int vertex_indices\n"
                                                "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
                                                "0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 0 0 0\n4 0 1 2 3 0 255 0\n");
  const TexturedMesh m = read_ply(ply);
  ASSERT_EQ(m.corner_color.size(), 6u);
  for (const auto& c : m.corner_color) expect_colour(c, 0, 1, 0);
}

TEST_F(VertexColours, PlyWithNeitherUvsNorColoursIsRefusedOnOneLine) {
  const std::string ply = write("bare.ply", std::string(kQuadHeader) +
                                                "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                                "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  const std::string e = error_of([](const std::string& p) { read_ply(p); }, ply);
  EXPECT_NE(e.find("bare.ply"), std::string::npos) << e;
  EXPECT_NE(e.find("nor colours"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

TEST_F(VertexColours, ObjVertexColoursFromZeroToOneOrTo255) {
  const std::string unit = write("unit.obj", "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 0.5\nf 1 2 3\n");
  const TexturedMesh a = read_obj(unit);
  ASSERT_EQ(a.corner_color.size(), 3u);
  expect_colour(a.corner_color[2], 0, 0, 0.5);
  ASSERT_EQ(a.corner_uv.size(), 3u);

  const std::string bytes = write("bytes.obj", "v 0 0 0 255 0 0\nv 1 0 0 0 255 0\nv 0 1 0 0 0 51\nf 1 2 3\n");
  expect_colour(read_obj(bytes).corner_color[2], 0, 0, 0.2);

  // A vertex without a colour: the model is not vertex-coloured, and then every face needs vt.
  const std::string partial = write("partial.obj", "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n");
  const std::string e = error_of([](const std::string& p) { read_obj(p); }, partial);
  EXPECT_NE(e.find("partial.obj"), std::string::npos) << e;
  EXPECT_NE(e.find("vertex colours"), std::string::npos) << e;

  const std::string negative = write("negative.obj", "v 0 0 0 -1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n");
  EXPECT_NE(error_of([](const std::string& p) { read_obj(p); }, negative).find("negative.obj:1:"), std::string::npos);
}

/// A catalogue mesh with random colours in [lo, hi] at its vertices. In [0.35, 0.65] every cell's
/// extrapolated fourth texel c1 + c2 - c0 stays inside [0, 1]; beyond it, some are clamped.
TexturedMesh randomly_coloured(const TexturedMesh& textured, unsigned seed, float lo = 0.35f, float hi = 0.65f) {
  TexturedMesh m = cat::vertex_coloured(textured);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> colour(lo, hi);
  std::vector<std::array<float, 4>> per_vertex(m.num_vertices());
  for (auto& c : per_vertex) c = {colour(rng), colour(rng), colour(rng), 1.0f};
  for (size_t t = 0; t < m.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k) m.corner_color[3 * t + size_t(k)] = per_vertex[m.triangles[t][size_t(k)]];
  return m;
}

TEST(VertexColourTexture, BilinearSamplesInsideEachTriangleInterpolateItsColours) {
  TexturedMesh m = randomly_coloured(cat::sphere(), 7);
  const TexturedMesh before = m;
  ASSERT_EQ(texture_vertex_colours(m), m.num_triangles());
  ASSERT_EQ(m.textures.size(), 1u);
  EXPECT_TRUE(m.textures[0].from_vertex_colours);
  EXPECT_EQ(m.positions, before.positions);
  EXPECT_EQ(m.triangles, before.triangles);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  size_t exact = 0, samples = 0;
  for (size_t t = 0; t < m.num_triangles(); ++t) {
    // The cell's fourth texel is c1 + c2 - c0; where that leaves [0, 1] it is clamped and only the
    // corners' own texels are exact.
    bool in_range = true;
    for (int ch = 0; ch < 3; ++ch) {
      const float x = m.corner_color[3 * t + 1][size_t(ch)] + m.corner_color[3 * t + 2][size_t(ch)] - m.corner_color[3 * t][size_t(ch)];
      in_range = in_range && x >= 0 && x <= 1;
    }
    for (int s = 0; s < 4; ++s) {
      double b1 = unit(rng), b2 = unit(rng);
      if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
      const double b[3] = {1 - b1 - b2, b1, b2};
      Vec2 uv = Vec2::Zero();
      std::array<double, 3> expected{0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        uv += b[k] * m.corner_uv[3 * t + size_t(k)];
        for (int ch = 0; ch < 3; ++ch) expected[size_t(ch)] += b[k] * m.corner_color[3 * t + size_t(k)][size_t(ch)];
      }
      const std::array<float, 4> got = sample_bilinear(m.textures[0].image, uv.x(), uv.y());
      double worst = 0;
      for (int ch = 0; ch < 3; ++ch) worst = std::max(worst, std::abs(got[size_t(ch)] / 255.0 - expected[size_t(ch)]));
      if (in_range) {
        EXPECT_LE(worst, 1.0 / 255.0) << "triangle " << t;  // 8-bit rounding of the texels, at most half a step each
        ++exact;
      }
      ++samples;
    }
  }
  EXPECT_EQ(exact, samples) << "every cell has its fourth texel in range";
}

TEST(VertexColourTexture, TexturedFacesKeepTheirTextureAndKdMultipliesTheColours) {
  TexturedMesh m = randomly_coloured(cat::multi_component(), 3);
  // Give the first triangle back a textured material: it keeps its texture and UVs.
  const TexturedMesh original = cat::multi_component();
  m.materials = original.materials;
  m.textures = original.textures;
  m.face_material[0] = 0;
  m.corner_uv[0] = original.corner_uv[0];
  Material tinted;
  tinted.name = "tinted";
  tinted.kd = {0.5, 1.0, 1.0};
  m.materials.push_back(tinted);
  m.face_material[1] = 1;
  ASSERT_EQ(texture_vertex_colours(m), m.num_triangles() - 1);
  EXPECT_EQ(m.face_material[0], 0);
  EXPECT_EQ(m.corner_uv[0], original.corner_uv[0]);
  const Image& colours = m.textures.back().image;
  // Triangle 1, corner 0: its texel is the colour times Kd in linear light.
  const Vec2 corner = m.corner_uv[3];
  const std::array<float, 4> got = sample_bilinear(colours, corner.x(), corner.y());
  EXPECT_NEAR(got[0] / 255.0, linear_to_srgb(0.5 * srgb_to_linear(m.corner_color[3][0])), 0.6 / 255.0);
  EXPECT_NEAR(got[1] / 255.0, m.corner_color[3][1], 0.6 / 255.0);
}

/// Runs the CLI; returns its report.
nlohmann::json run_cli(const fs::path& input, const fs::path& out, const std::string& options) {
  const std::string cmd = std::string(TIGHTEX_CLI) + " '" + input.string() + "' -o '" + out.string() + "' --quiet " + options;
  const int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cmd;
  std::ifstream f(out / "report.json");
  return f ? nlohmann::json::parse(f) : nlohmann::json::object();
}

/// Per corner of `result` (the output of the command line on `coloured`, its triangles in the same
/// order), the output texture read bilinearly at the corner's UV against the corner's vertex colour as
/// written to the file (8 bits): the mean of the red, green and blue errors, in 1/255, ascending.
std::vector<double> corner_colour_errors(const TexturedMesh& coloured, const TexturedMesh& result) {
  std::vector<double> errors;
  EXPECT_EQ(result.num_triangles(), coloured.num_triangles());
  for (size_t t = 0; t < std::min(result.num_triangles(), coloured.num_triangles()); ++t) {
    const Image& image = result.textures[size_t(result.materials[size_t(result.face_material[t])].texture)].image;
    for (int k = 0; k < 3; ++k) {
      const Vec3 moved = result.positions[result.triangles[t][size_t(k)]] - coloured.positions[coloured.triangles[t][size_t(k)]];
      EXPECT_LT(moved.norm(), 1e-5) << "triangle " << t << " is not where the input has it";
      if (moved.norm() >= 1e-5) return {};
      const Vec2 uv = result.sampled_uv(t, k);
      const std::array<float, 4> got = sample_bilinear(image, uv.x(), uv.y());
      const std::array<float, 4>& want = coloured.corner_color[3 * t + size_t(k)];
      double e = 0;
      for (size_t ch = 0; ch < 3; ++ch) e += std::abs(got[ch] - double(cat::colour_byte(want[ch])));
      errors.push_back(e / 3);
    }
  }
  std::sort(errors.begin(), errors.end());
  return errors;
}

/// The command line on a vertex-coloured PLY and OBJ made from `textured`: a textured model of the same
/// kind comes out, one fold-free chart per component, every triangle kept, its texture reproducing the
/// colours (measured against the model as read_model reads it) above `min_psnr`.
void expect_vertex_colours_baked(const TexturedMesh& textured, const fs::path& dir, double min_psnr, const std::string& options) {
  const TexturedMesh coloured = cat::vertex_coloured(textured);
  cat::write_vertex_coloured_ply(coloured, (dir / "scan.ply").string());
  cat::write_vertex_coloured_obj(coloured, (dir / "scan.obj").string());
  for (const char* kind : {"ply", "obj"}) {
    const fs::path input = dir / (std::string("scan.") + kind), out = dir / (std::string("out_") + kind);
    const nlohmann::json report = run_cli(input, out, options);
    ASSERT_TRUE(report.contains("metrics")) << kind;
    EXPECT_EQ(report["input"]["vertex_coloured_triangles"].get<size_t>(), coloured.num_triangles());
    const TexturedMesh in = read_model(input.string()), result = read_model((out / (std::string("scan.") + kind)).string());
    EXPECT_TRUE(result.corner_color.empty()) << "the output is textured";
    ASSERT_EQ(result.textures.size(), 1u);
    EXPECT_FALSE(result.textures[0].from_vertex_colours);
    const Metrics m = measure(in, result, 50000);
    EXPECT_EQ(m.lost_triangles, 0u) << kind;
    EXPECT_EQ(m.flipped, 0u) << kind;
    EXPECT_EQ(m.charts, report["preparation"]["components"].get<size_t>()) << kind;
    EXPECT_GT(m.surface_psnr, min_psnr) << kind;
    // The vertex colours come back at the vertices: mean within 1/255, P99 within 4.
    const std::vector<double> errors = corner_colour_errors(coloured, result);
    ASSERT_FALSE(errors.empty());
    EXPECT_LE(std::accumulate(errors.begin(), errors.end(), 0.0) / double(errors.size()), 1.0) << kind;
    EXPECT_LE(errors[size_t(0.99 * double(errors.size()))], 4.0) << kind;
  }
}

TEST_F(VertexColours, CommandLineBakesTheColoursOfAGeneratedScan) {
  // The sphere's gradient texture seen at its vertices; the default budget (kTexelsPerColouredTriangle).
  expect_vertex_colours_baked(cat::sphere(), dir_, 40.0, "");
}

TEST_F(VertexColours, CommandLineBakesTheColoursOfARealScan) {
  const fs::path obj = fs::path(TIGHTEX_REPO_DATA) / "fuze" / "fuze.obj";
  // Measured 41.8 dB for the PLY at the default budget (64 x 64 texels for 1k triangles).
  expect_vertex_colours_baked(read_obj(obj.string()), dir_, 38.0, "");
}

}  // namespace
}  // namespace tightex
