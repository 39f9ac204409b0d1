// Every real scan through the tightex command, its written output read back and measured
// independently of the tool's own report (docs/metrics.md): the one in the repository (tests/data/fuze,
// so a fresh clone runs the real-data path and its quality gate) and those of ../shared/data where it
// is present (the tests that need one of those skip without it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "io/obj_reader.hpp"
#include "pipeline/aspect.hpp"
#include "report/metrics.hpp"
#include "tightex/run.hpp"
#include "tightex/tightex.hpp"

namespace fs = std::filesystem;
using namespace tightex;

namespace {

/// The repository's scan (tests/data/fuze, MIT), the one every checkout has.
const fs::path kFuze = fs::path(TIGHTEX_REPO_DATA) / "fuze" / "fuze.obj";

/// The OBJ models of tests/data, then those of ../shared/data (where present) whose folder name is not
/// already taken by the repository's: one entry per model folder, sorted within each root.
std::vector<std::string> data_models() {
  std::vector<std::string> models;
  std::set<std::string> folders;
  for (const fs::path root : {fs::path(TIGHTEX_REPO_DATA), fs::path(TIGHTEX_SHARED_DATA)}) {
    if (!fs::is_directory(root)) continue;
    std::vector<std::string> found;
    for (const auto& dir : fs::directory_iterator(root))
      if (dir.is_directory() && !folders.contains(dir.path().filename().string()))
        for (const auto& f : fs::directory_iterator(dir.path()))
          if (f.path().extension() == ".obj") found.push_back(f.path().string());
    std::sort(found.begin(), found.end());
    for (const std::string& m : found) folders.insert(fs::path(m).parent_path().filename().string());
    models.insert(models.end(), found.begin(), found.end());
  }
  return models;
}

class RealData : public ::testing::TestWithParam<std::string> {};

TEST_P(RealData, CliOutputIsOneFoldFreeChartPerComponentFillingTheTexture) {
  const std::string input = GetParam();
  const fs::path out =
      fs::temp_directory_path() / ("tightex_real_" + fs::path(input).parent_path().filename().string() + "_" + std::to_string(::getpid()));
  fs::remove_all(out);
  // The default run. Under AddressSanitizer (CI's second pass, several times slower) only fuze, the
  // smallest model, probes the texture's shape; the others keep the square (--aspect 1), which the
  // first pass has already run as part of the default; and the four YCB scans, whose default textures
  // are 2700-3400 texels a side, bake at --size 1024 (under the sanitizers 45-65 s each at their
  // default, mostly the bake and its fit, the soup can's three probes too): the first pass checks
  // their default budget, fidelity and the soup can's shape. That keeps CI within its time.
#ifdef __SANITIZE_ADDRESS__
  const bool probe_shape = input.find("/fuze/") != std::string::npos;
  const bool default_budget = input.find("/ycb_") == std::string::npos;
#else
  const bool probe_shape = true, default_budget = true;
#endif
  const std::string cmd = std::string(TIGHTEX_CLI) + " '" + input + "' -o '" + out.string() + "' --quiet" +
                          (probe_shape ? "" : " --aspect 1") + (default_budget ? "" : " --size 1024");
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;

  const TexturedMesh in = read_obj(input);
  const TexturedMesh result = read_obj((out / (fs::path(input).stem().string() + ".obj")).string());
  const Metrics m = measure(in, result);
  std::ifstream report_file(out / "report.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  const size_t components = report["preparation"]["components"].get<size_t>();

  EXPECT_EQ(m.lost_triangles, 0u);
  EXPECT_EQ(m.flipped, 0u);
  EXPECT_EQ(m.degenerate, 0u);
  EXPECT_EQ(m.overlap, 0.0);
  EXPECT_EQ(m.charts, components);
  EXPECT_GE(m.output.utilization, 0.99);
  EXPECT_EQ(result.textures.size(), 1u);
  // The default budget keeps the input's information: as many texels as the input uses, in a square
  // whose side is a multiple of 4.
  const int side = report["options"]["size"].get<int>();
  EXPECT_EQ(side % 4, 0);
  if (default_budget) {
    EXPECT_EQ(side, size_for_texels(std::ceil(m.input.used_texels / 4.0) * 4.0));
    EXPECT_GE(double(m.output.texels), m.input.used_texels);
    // Colour fidelity at that budget (default detail map): measured 42.1 (fuze) to 57.6 dB (bust).
    EXPECT_GT(m.surface_psnr, 38.0);
  } else {
    EXPECT_EQ(side, 1024);
  }
  // Colours sit where they were: the real result beats the same result with its texture mirrored by
  // a wide margin.
  TexturedMesh mirrored = result;
  for (Vec2& uv : mirrored.corner_uv) uv.x() = 1.0 - uv.x();
  const Metrics wrong = measure(in, mirrored, 50000);
  EXPECT_GT(m.surface_psnr, wrong.surface_psnr + 3.0) << "mirrored control: " << wrong.surface_psnr;
  // The texture's shape (auto): the texture is W x H of the chosen aspect, the chosen shape is the
  // square unless another was estimated at least 5% closer (then the best), on the shapes' own maps
  // where a large component was chosen on them (full_map_estimated_psnr_db), and the soup can,
  // whose side unrolls to about 2:1, gets a long texture (docs/maps.md, "The texture's shape").
  const nlohmann::json& shape = report["aspect"];
  const double chosen = shape["chosen"].get<double>();
  EXPECT_EQ(chosen == 1.0, result.textures[0].image.width == result.textures[0].image.height);
  if (chosen != 1.0) EXPECT_EQ(chosen > 1.0, result.textures[0].image.width > result.textures[0].image.height);
  bool on_own_maps = false;
  for (const auto& p : shape["probes"]) on_own_maps = on_own_maps || !p["full_map_estimated_psnr_db"].is_null();
  const char* estimate = on_own_maps ? "full_map_estimated_psnr_db" : "estimated_psnr_db";
  double best = -1, square = -1;
  for (const auto& p : shape["probes"]) {
    const double db = p[estimate].is_null() ? -1.0 : p[estimate].get<double>(), a = p["aspect"].get<double>();
    if (a == 1.0) square = db;
    if (a == chosen) EXPECT_EQ(result.textures[0].image.width, p["width"].get<int>());
    best = std::max(best, db);
  }
  if (!shape["probes"].empty()) {
    for (const auto& p : shape["probes"])
      if (p["aspect"].get<double>() == chosen) EXPECT_TRUE(chosen == 1.0 ? best - square < 0.23 : p[estimate].get<double>() == best);
  }
  // A can's side unrolls to about 2:1: a long texture (1:2 or 2:1, as the cut turns it).
  if (probe_shape && input.find("tomato_soup_can") != std::string::npos) EXPECT_NE(chosen, 1.0);
  if (!probe_shape) EXPECT_TRUE(shape["probes"].empty());
  // The report states the same figures as the independent measurement.
  EXPECT_EQ(report["metrics"]["lost_triangles"].get<size_t>(), m.lost_triangles);
  EXPECT_NEAR(report["metrics"]["output"]["utilization"].get<double>(), m.output.utilization, 1e-9);
  fs::remove_all(out);
}

/// Runs the CLI with `options` and returns its report (the docs/metrics.md figures it measured).
nlohmann::json run_cli(const std::string& input, const std::string& options, const std::string& tag) {
  const fs::path out = fs::temp_directory_path() /
                       ("tightex_" + tag + "_" + fs::path(input).parent_path().filename().string() + "_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const std::string cmd = std::string(TIGHTEX_CLI) + " '" + input + "' -o '" + out.string() + "' --quiet " + options;
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream report_file(out / "report.json");
  nlohmann::json report = report_file ? nlohmann::json::parse(report_file) : nlohmann::json::object();
  fs::remove_all(out);
  return report;
}

// --map area spreads the texels evenly, 90% of the surface within a factor 2 of the mean density (the
// spread does not depend on the size; a small one keeps the bake cheap). On these models it holds with
// room to spare, within a factor 2^0.5 (measured at this size: P5 -0.34 at worst, the dancing girl;
// meshroom_esp32cam -0.24), so that is what is asserted: unseen scans need the margin.
TEST_P(RealData, AreaMapKeepsNinetyPercentWithinAFactorTwoOfTheMeanDensity) {
  // Under AddressSanitizer (CI's second pass) in the square only: the first pass runs the texture-shape
  // probes, whose choice it checks; the flow and the refinement run either way.
#ifdef __SANITIZE_ADDRESS__
  const char* shape = " --aspect 1";
#else
  const char* shape = "";
#endif
  const nlohmann::json r = run_cli(GetParam(), std::string("--map area --size 256 --no-fit") + shape, "area");
  ASSERT_TRUE(r.contains("metrics"));
  EXPECT_EQ(r["metrics"]["flipped"].get<size_t>(), 0u);
  EXPECT_EQ(r["metrics"]["lost_triangles"].get<size_t>(), 0u);
  EXPECT_GE(r["metrics"]["density_spread"]["p5"].get<double>(), -0.5);
  EXPECT_LE(r["metrics"]["density_spread"]["p95"].get<double>(), 0.5);
}

INSTANTIATE_TEST_SUITE_P(Scans, RealData, ::testing::ValuesIn(data_models()), [](const ::testing::TestParamInfo<std::string>& info) {
  std::string n = fs::path(info.param).parent_path().filename().string();
  for (char& c : n)
    if (!isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
});
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(RealData);

// The Meshroom scan at --size 1024: the default map reaches texture-defrag's 41.3 dB (in
// 40% of its texels) and beats the paper's harmonic map by at least 3 dB (measured 41.70 vs 35.74).
TEST(RealDataMaps, DefaultMapBeatsHarmonicAndTextureDefragOnMeshroomAt1024) {
  const fs::path input = fs::path(TIGHTEX_SHARED_DATA) / "meshroom_esp32cam" / "texturedMesh.obj";
  if (!fs::exists(input)) GTEST_SKIP() << "../shared/data/meshroom_esp32cam not present";
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "figures only: the first CI pass measures them, RealData runs the model under the sanitizers";
#endif
  const nlohmann::json def = run_cli(input.string(), "--size 1024", "default"),
                       harm = run_cli(input.string(), "--size 1024 --map harmonic", "harmonic");
  ASSERT_TRUE(def.contains("metrics") && harm.contains("metrics"));
  const double d = def["metrics"]["surface_psnr_db"].get<double>(), h = harm["metrics"]["surface_psnr_db"].get<double>();
  EXPECT_GE(d, 41.3);
  EXPECT_GE(d, h + 3.0);
  EXPECT_EQ(def["metrics"]["flipped"].get<size_t>(), 0u);
  EXPECT_EQ(harm["metrics"]["flipped"].get<size_t>(), 0u);
}

// The real-data tests above always run on at least the repository's scan, whether ../shared/data is
// there or not, and each model folder is run once (a folder of both roots: the repository's copy).
TEST(RealDataPresence, TheRepositoryScanIsAlwaysAmongTheModels) {
  ASSERT_TRUE(fs::is_regular_file(kFuze)) << kFuze;
  const std::vector<std::string> models = data_models();
  EXPECT_EQ(std::count(models.begin(), models.end(), kFuze.string()), 1);
  std::set<std::string> folders;
  for (const std::string& m : models) EXPECT_TRUE(folders.insert(fs::path(m).parent_path().filename().string()).second) << m;
}

}  // namespace

namespace {

std::string file_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// Same input and options: byte-identical output, whatever the scheduling (run once on one core).
TEST(RealDataDeterminism, SameInputGivesByteIdenticalOutput) {
  const fs::path input = kFuze;
  const std::string pid = std::to_string(::getpid());
  const fs::path a = fs::temp_directory_path() / ("tightex_det_a_" + pid), b = fs::temp_directory_path() / ("tightex_det_b_" + pid);
  fs::remove_all(a);
  fs::remove_all(b);
  const std::string cli = std::string(TIGHTEX_CLI) + " '" + input.string() + "' --size 1024 --quiet -o ";
  ASSERT_EQ(std::system((cli + "'" + a.string() + "'").c_str()), 0);
  ASSERT_EQ(std::system(("taskset -c 0 " + cli + "'" + b.string() + "' 2>/dev/null || " + cli + "'" + b.string() + "'").c_str()), 0);
  for (const char* name : {"fuze.obj", "fuze.mtl", "fuze_tightex.jpg"}) {  // JPEG in, JPEG out (the quality rate control picks)
    SCOPED_TRACE(name);
    const std::string x = file_bytes(a / name), y = file_bytes(b / name);
    EXPECT_FALSE(x.empty());
    EXPECT_TRUE(x == y);
  }
  fs::remove_all(a);
  fs::remove_all(b);
}

}  // namespace

namespace {

// Resource guard: refused before anything is allocated or written, exit code 1, no output left.
TEST(RealDataGuards, OversizeAndOverBudgetRunsAreRefusedWithoutOutput) {
  const fs::path input = kFuze;
  const fs::path out = fs::temp_directory_path() / ("tightex_guard_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const std::string cli = std::string(TIGHTEX_CLI) + " '" + input.string() + "' -o '" + out.string() + "' --quiet 2>/dev/null ";
  for (const char* options : {"--size 20000", "--max-memory 1"}) {
    SCOPED_TRACE(options);
    const int status = std::system((cli + options).c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 1);
    EXPECT_FALSE(fs::exists(out));
  }
}

// The guard's estimate bounds what the run holds: the peak meshroom_esp32cam's run reports is below the
// memory the guard estimates for it (estimate_memory, what --max-memory is checked against).
TEST(RealDataGuards, TheEstimateIsAboveTheRunsPeak) {
  const fs::path input = fs::path(TIGHTEX_SHARED_DATA) / "meshroom_esp32cam" / "texturedMesh.obj";
  if (!fs::exists(input)) GTEST_SKIP() << "../shared/data/meshroom_esp32cam not present";
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "the sanitizers' shadow memory is not the run's";
#endif
  const nlohmann::json report = run_cli(input.string(), "", "peak");
  ASSERT_TRUE(report.contains("peak_rss_mib"));
  EXPECT_LT(report["peak_rss_mib"].get<double>(), estimate_memory(input.string()) / double(1 << 20));
}

}  // namespace

// At the default budget (the input's used texels) on the mustard bottle, whose harmonic map is
// already nearly even and conformal: the default map still beats it by 3 dB (measured 53.73 vs 50.66),
// by giving the label's print the texels the plain plastic does not need.
TEST(RealDataMaps, DefaultMapBeatsHarmonicByThreeDecibelsOnTheMustardBottle) {
  const fs::path input = fs::path(TIGHTEX_SHARED_DATA) / "ycb_006_mustard_bottle" / "006_mustard_bottle_textured.obj";
  if (!fs::exists(input)) GTEST_SKIP() << "../shared/data/ycb_006_mustard_bottle not present";
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "figures only: the first CI pass measures them, RealData runs the model under the sanitizers";
#endif
  const nlohmann::json def = run_cli(input.string(), "", "default"), harm = run_cli(input.string(), "--map harmonic", "harmonic");
  ASSERT_TRUE(def.contains("metrics") && harm.contains("metrics"));
  EXPECT_EQ(def["options"]["size"], harm["options"]["size"]);
  EXPECT_GE(def["metrics"]["surface_psnr_db"].get<double>(), harm["metrics"]["surface_psnr_db"].get<double>() + 3.0);
  EXPECT_EQ(def["metrics"]["flipped"].get<size_t>(), 0u);
}

// --map area on the potted meat can: its refinement's 4 Newton steps together widen the density
// error past the 0.1 slack, its first alone does not. Step by step, that one is kept (45.19 dB); the
// whole refinement undone gave 44.82.
TEST(RealDataMaps, AreaMapKeepsTheRefinementStepsWithinTheDensitySlack) {
  const fs::path input = fs::path(TIGHTEX_SHARED_DATA) / "ycb_010_potted_meat_can" / "010_potted_meat_can_textured.obj";
  if (!fs::exists(input)) GTEST_SKIP() << "../shared/data/ycb_010_potted_meat_can not present";
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "figures only: the first CI pass measures them";
#endif
  const nlohmann::json r = run_cli(input.string(), "--map area --no-html", "area_slack");
  ASSERT_TRUE(r.contains("metrics"));
  const nlohmann::json& map = r["components"][0];
  EXPECT_GE(map["refine_iterations"].get<int>(), 1);
  EXPECT_EQ(map["refine_stopped"], "density");
  EXPECT_GT(r["metrics"]["surface_psnr_db"].get<double>(), 45.0);
  EXPECT_EQ(r["metrics"]["flipped"].get<size_t>(), 0u);
}

// A component large enough for its probes to be multilevel (meshroom_esp32cam: 53k faces) is not
// probed: its coarse copy's texel stretch decides whether another shape's own map is made beside the
// square's. Meshroom's is within kShapeLookStretch (1.07; 1.48 while the rim's ears were crushed onto
// the square's sides): its square alone is mapped, nothing is estimated, and the square is kept.
TEST(RealDataMaps, ALargeComponentWithMildStretchKeepsItsSquareOnOneMap) {
  const fs::path input = fs::path(TIGHTEX_SHARED_DATA) / "meshroom_esp32cam" / "texturedMesh.obj";
  if (!fs::exists(input)) GTEST_SKIP() << "../shared/data/meshroom_esp32cam not present";
#ifdef __SANITIZE_ADDRESS__
  GTEST_SKIP() << "the first CI pass runs it; the sanitizer pass runs the same code on fuze's probes";
#endif
  const nlohmann::json r = run_cli(input.string(), "--no-html", "own_maps");
  ASSERT_TRUE(r.contains("metrics"));
  const nlohmann::json& aspect = r["aspect"];
  const nlohmann::json& probes = aspect["probes"];
  ASSERT_EQ(probes.size(), 3u);
  const double stretch = aspect["square_texel_stretch"].get<double>();
  EXPECT_LT(stretch, kShapeLookStretch);
  EXPECT_GT(stretch, 1 / kShapeLookStretch);
  for (const nlohmann::json& p : probes) {
    EXPECT_EQ(p["estimated_psnr_db"].get<double>(), -1.0) << p;
    EXPECT_TRUE(p["full_map_estimated_psnr_db"].is_null()) << p;
  }
  EXPECT_EQ(aspect["chosen"].get<double>(), 1.0);
  // Measured 45.25 dB.
  EXPECT_GT(r["metrics"]["surface_psnr_db"].get<double>(), 43.8);
  EXPECT_EQ(r["metrics"]["flipped"].get<size_t>(), 0u);
  EXPECT_EQ(r["metrics"]["lost_triangles"].get<size_t>(), 0u);
}
