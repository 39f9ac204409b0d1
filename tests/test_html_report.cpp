// report.html: the page's data (decimated views, seams, density, textures, its size) and the page itself, and the
// command line's --no-html. The page in a browser: tests/browser (ctest Browser.ReportPage).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "command_line.hpp"
#include "mesh_catalogue.hpp"
#include "report/html_report.hpp"
#include "report/metrics.hpp"
#include "report/view_mesh.hpp"
#include "tightex/tightex.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;
using namespace tightex::testing;

/// Decodes standard base64 (the page's typed arrays).
std::vector<unsigned char> from_base64(const std::string& text) {
  std::vector<unsigned char> out;
  uint32_t word = 0;
  int bits = 0;
  for (char c : text) {
    const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char* at = c == '=' ? nullptr : std::strchr(digits, c);
    if (at == nullptr) break;
    word = (word << 6) | uint32_t(at - digits);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back((unsigned char)((word >> bits) & 0xff));
    }
  }
  return out;
}

/// A typed array of the page's data, read back.
template <typename T>
std::vector<T> array_of(const nlohmann::json& model, const char* key) {
  const std::vector<unsigned char> bytes = from_base64(model[key].get<std::string>());
  std::vector<T> values(bytes.size() / sizeof(T));
  if (!values.empty()) std::memcpy(values.data(), bytes.data(), values.size() * sizeof(T));
  return values;
}

/// The data html_model_data gives for `input` and `output`, parsed.
nlohmann::json model_data(const TexturedMesh& input, const TexturedMesh& output, size_t max_triangles) {
  HtmlReportOptions options;
  options.max_triangles = max_triangles;
  return nlohmann::json::parse(html_model_data(input, output, options));
}

/// Two triangles sharing the edge (1, 2) of a unit square, with texture coordinates `uv` per corner.
TexturedMesh square(const std::vector<Vec2>& uv) {
  TexturedMesh m = make_textured("square", {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {1.0, 1.0, 0.0}}, {{0, 1, 2}, {2, 1, 3}});
  m.corner_uv = uv;
  return m;
}

TEST(HtmlReport, SeamsAreWhereTheTextureCoordinatesJump) {
  // One chart: the shared edge is no seam; every other edge is the border.
  const TexturedMesh joined = square({{0, 0}, {1, 0}, {0, 1}, {0, 1}, {1, 0}, {1, 1}});
  const std::vector<uint8_t> seams = array_of<uint8_t>(model_data(joined, joined, 100)["models"][0], "seams");
  ASSERT_EQ(seams.size(), 2u);
  EXPECT_EQ(seams[0], 0b101);  // its edge 1 (corner 1 to 2) is the shared one
  EXPECT_EQ(seams[1], 0b110);
  // The second triangle moved in texture space: the shared edge is a seam on both sides.
  const TexturedMesh split = square({{0, 0}, {1, 0}, {0, 1}, {0.5, 1}, {1.5, 0}, {1.5, 1}});
  const std::vector<uint8_t> split_seams = array_of<uint8_t>(model_data(split, split, 100)["models"][0], "seams");
  EXPECT_EQ(split_seams[0], 0b111);
  EXPECT_EQ(split_seams[1], 0b111);
}

TEST(HtmlReport, ChartCountsAreTheMeasures) {
  // The command line takes the page's chart counts from the measure: the same data as counted here.
  const TexturedMesh split = square({{0, 0}, {1, 0}, {0, 1}, {0.5, 1}, {1.5, 0}, {1.5, 1}});
  const TexturedMesh joined = square({{0, 0}, {1, 0}, {0, 1}, {0, 1}, {1, 0}, {1, 1}});
  const WeldedEdges split_edges = welded_edges(split), joined_edges = welded_edges(joined);
  const Metrics m = measure(split, joined, split_edges, joined_edges, 1000);
  EXPECT_EQ(m.charts_input, 2u);
  EXPECT_EQ(m.charts, 1u);
  const std::string counted = html_model_data(split, joined);
  EXPECT_EQ(html_model_data(html_model_data_without_charts(split, joined, split_edges, joined_edges), m.charts_input, m.charts), counted);
  const nlohmann::json data = nlohmann::json::parse(counted);
  EXPECT_EQ(data["models"][0]["charts"], 2);
  EXPECT_EQ(data["models"][1]["charts"], 1);
}

TEST(HtmlReport, DensityIsRelativeToTheMean) {
  // The second triangle has four times the first's texture area on the same 3D area.
  const TexturedMesh m = square({{0, 0}, {0.25, 0}, {0, 0.25}, {0, 0.5}, {0.5, 0}, {0.5, 0.5}});
  const std::vector<float> density = array_of<float>(model_data(m, m, 100)["models"][1], "density");
  ASSERT_EQ(density.size(), 2u);
  EXPECT_NEAR(density[1] - density[0], 2.0, 1e-5);                        // log2 of 4
  EXPECT_NEAR(std::exp2(density[0]) + std::exp2(density[1]), 2.0, 1e-5);  // mean of equal areas is 1
}

TEST(HtmlReport, DecimatedViewsShowTheSameSurfaceInBothModels) {
  const TexturedMesh input = sphere();
  // The output: the same triangles in another order, corners rotated, vertices renumbered.
  TexturedMesh output = input;
  const size_t n = input.num_triangles(), nv = input.num_vertices();
  for (size_t t = 0; t < n; ++t) {
    const Tri& f = input.triangles[n - 1 - t];
    output.triangles[t] = {uint32_t(nv - 1 - f[1]), uint32_t(nv - 1 - f[2]), uint32_t(nv - 1 - f[0])};
  }
  for (size_t v = 0; v < nv; ++v) output.positions[nv - 1 - v] = input.positions[v];
  const nlohmann::json data = model_data(input, output, n / 4);
  const nlohmann::json &in = data["models"][0], &out = data["models"][1];
  EXPECT_EQ(in["triangles"], n);
  EXPECT_GT(in["shown"].get<size_t>(), n / 16);
  EXPECT_LE(in["shown"].get<size_t>(), n / 4);
  EXPECT_EQ(in["shown"], out["shown"]);
  // The same surface: compare the sorted corner positions of each shown triangle (cell means, summed in
  // another order: to a millionth).
  auto shown_set = [](const nlohmann::json& model) {
    const std::vector<float> p = array_of<float>(model, "positions");
    const std::vector<uint32_t> idx = array_of<uint32_t>(model, "indices");
    std::vector<std::array<float, 9>> tris;
    for (size_t t = 0; t < idx.size() / 3; ++t) {
      std::array<std::array<float, 3>, 3> c;
      for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) c[k][a] = std::round(p[3 * idx[3 * t + k] + a] * 1e6f) / 1e6f;
      std::sort(c.begin(), c.end());
      tris.push_back({c[0][0], c[0][1], c[0][2], c[1][0], c[1][1], c[1][2], c[2][0], c[2][1], c[2][2]});
    }
    std::sort(tris.begin(), tris.end());
    return tris;
  };
  EXPECT_EQ(shown_set(in), shown_set(out));
  // Under the cap, everything is shown.
  EXPECT_EQ(model_data(input, output, n)["models"][1]["shown"], n);
}

/// A flat grid of `n` x `n` squares on [0, 1]^2, its texture coordinates (x + 5, y) right of x = 0.5:
/// two charts with a seam down the middle.
TexturedMesh two_chart_grid(int n) {
  std::vector<Vec3> positions;
  std::vector<Tri> triangles;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) positions.push_back(Vec3(double(i) / n, double(j) / n, 0));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = uint32_t(j * (n + 1) + i), b = a + 1, c = a + uint32_t(n) + 1, d = c + 1;
      triangles.push_back({a, b, d});
      triangles.push_back({a, d, c});
    }
  TexturedMesh m = make_textured("grid", positions, triangles);
  for (size_t t = 0; t < m.num_triangles(); ++t) {
    const bool right = m.positions[m.triangles[t][0]].x() + m.positions[m.triangles[t][1]].x() + m.positions[m.triangles[t][2]].x() > 1.5;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = m.positions[m.triangles[t][k]];
      m.corner_uv[3 * t + k] = Vec2(p.x() + (right ? 5 : 0), p.y());
    }
  }
  return m;
}

TEST(HtmlReport, DecimationKeepsTextureCoordinatesAndSeams) {
  const TexturedMesh grid = two_chart_grid(120);
  const double cell = cluster_cell(grid, 2000);
  ASSERT_GT(cell, 0);
  const TexturedMesh view = clustered_mesh(grid, cell);
  EXPECT_LE(view.num_triangles(), 2000u);
  EXPECT_GT(view.num_triangles(), 500u);
  for (size_t t = 0; t < view.num_triangles(); ++t) {
    // No triangle spans the seam's jump of 5 in u; each corner's coordinate stays near its position's.
    double lo = 1e9, hi = -1e9;
    for (int k = 0; k < 3; ++k) {
      const Vec2 uv = view.corner_uv[3 * t + k];
      const Vec3& p = view.positions[view.triangles[t][k]];
      lo = std::min(lo, uv.x()), hi = std::max(hi, uv.x());
      EXPECT_NEAR(uv.x() - (uv.x() > 3 ? 5 : 0), p.x(), 2 * cell) << t;
      EXPECT_NEAR(uv.y(), p.y(), 2 * cell) << t;
    }
    EXPECT_LT(hi - lo, 4 * cell) << t;
  }
  // Both charts are shown, in the page's data too.
  const std::vector<float> uv = array_of<float>(model_data(grid, grid, 2000)["models"][1], "uv");
  size_t left = 0, right = 0;
  for (size_t i = 0; i < uv.size(); i += 2) ++(uv[i] > 3 ? right : left);
  EXPECT_GT(left, uv.size() / 8);
  EXPECT_GT(right, uv.size() / 8);
}

TEST(HtmlReport, PageStaysUnderThreeMegabytesForALargeModel) {
  // A fine grid with a large texture of noise (JPEG's worst case) on both models.
  TexturedMesh grid = two_chart_grid(400);  // 320,000 triangles
  Image noise(4096, 4096);
  uint64_t state = 1;
  for (Rgba8& p : noise.pixels) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    p = Rgba8{uint8_t(state >> 56), uint8_t(state >> 48), uint8_t(state >> 40), 255};
  }
  grid.textures[0].image = noise;
  TexturedMesh output = grid;
  output.textures.push_back(output.textures[0]);  // a second page
  const std::string data = html_model_data(grid, output);
  const std::string page = html_report_page("{}", data);
  EXPECT_LE(page.size(), 3000000u);
  const nlohmann::json models = nlohmann::json::parse(data)["models"];
  EXPECT_LE(models[0]["shown"].get<size_t>(), HtmlReportOptions{}.max_triangles);
  EXPECT_GT(models[0]["shown"].get<size_t>(), HtmlReportOptions{}.max_triangles / 4);
  EXPECT_EQ(models[1]["textures"].size(), 2u);
}

TEST(HtmlReport, PageHoldsEverythingAndNoMarker) {
  const TexturedMesh m = disk();
  const std::string report = R"({"input": {"file": "a</script><script>alert(1)</script>.obj"}})";
  const std::string page = html_report_page(report, html_model_data(m, m));
  EXPECT_EQ(page.find("TIGHTEX:"), std::string::npos);
  EXPECT_NE(page.find("REVISION=\"111\""), std::string::npos);  // three.js packed in
  EXPECT_NE(page.find("OrbitControls"), std::string::npos);
  EXPECT_NE(page.find("data:image/jpeg;base64,/9j/"), std::string::npos);  // the texture as a JPEG
  // A file name cannot end the script element that holds the report (the JSON escapes "<").
  EXPECT_EQ(page.find("a</script>"), std::string::npos);
  EXPECT_NE(page.find(R"(a\u003c/script>)"), std::string::npos);
  // Nothing that would make a browser reach out.
  for (const char* url : {"http://", "https://", "src=\"//"}) {
    size_t at = page.find(url);
    // three.js and the licence comment name web sites in strings and comments, never as a source.
    while (at != std::string::npos) {
      const std::string before = page.substr(at > 40 ? at - 40 : 0, std::min<size_t>(at, 40));
      EXPECT_EQ(before.find("src="), std::string::npos) << page.substr(at > 40 ? at - 40 : 0, 80);
      EXPECT_EQ(before.find("href="), std::string::npos) << page.substr(at > 40 ? at - 40 : 0, 80);
      at = page.find(url, at + 1);
    }
  }
}

std::string contents(const fs::path& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), {});
}

TEST(HtmlReport, CommandLineWritesThePageUnlessToldNotTo) {
  const fs::path dir = fs::temp_directory_path() / ("tightex_html_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  write_obj(sphere_with_holes(), (dir / "in").string(), "holey", ImageFormat::kPng);
  const std::string in = "'" + (dir / "in" / "holey.obj").string() + "' --size 128";
  ASSERT_EQ(testing::run_tightex(in + " -o '" + (dir / "page").string() + "' > '" + (dir / "stdout.txt").string() + "'"), 0);
  ASSERT_EQ(testing::run_tightex(in + " -o '" + (dir / "plain").string() + "' --no-html --quiet"), 0);

  EXPECT_TRUE(fs::exists(dir / "page" / "report.html"));
  EXPECT_FALSE(fs::exists(dir / "plain" / "report.html"));
  // The page changes no other output: model, material and texture are byte for byte the same.
  for (const char* name : {"holey.obj", "holey.mtl", "holey_tightex.png"})
    EXPECT_EQ(contents(dir / "page" / name), contents(dir / "plain" / name)) << name;
  const nlohmann::json report = nlohmann::json::parse(contents(dir / "page" / "report.json"));
  EXPECT_EQ(report["output"]["html"], "report.html");
  EXPECT_FALSE(nlohmann::json::parse(contents(dir / "plain" / "report.json"))["output"].contains("html"));
  // The page holds report.json as written (with "<" escaped), and the command names it last.
  std::string escaped;
  for (char c : contents(dir / "page" / "report.json")) escaped += c == '<' ? std::string("\\u003c") : std::string(1, c);
  EXPECT_NE(contents(dir / "page" / "report.html").find(escaped), std::string::npos);
  const std::string out = contents(dir / "stdout.txt");
  const std::string last = out.substr(out.rfind('\n', out.size() - 2) + 1);
  EXPECT_EQ(last, "tightex: report: " + (dir / "page" / "report.html").string() + "\n");
  // The page links the full-size texture written beside it.
  EXPECT_NE(contents(dir / "page" / "report.html").find(R"("file":"holey_tightex.png")"), std::string::npos);
  // No temporary file is left behind.
  for (const auto& e : fs::directory_iterator(dir / "page")) EXPECT_NE(e.path().filename().string()[0], '.') << e.path();
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tightex
