// Replays every file of fuzz/corpus/ (the fuzzers' seeds, and the inputs they found that once broke
// something) through the same entry points as the libFuzzer harnesses (fuzz/targets.hpp), in the
// normal build: each must be read or refused with an InputError, and nothing else.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "targets.hpp"

namespace {

namespace fs = std::filesystem;
using tightex_fuzz::Outcome;

std::vector<fs::path> corpus(const std::string& harness) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(fs::path(TIGHTEX_FUZZ_CORPUS) / harness))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::string bytes_of(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

template <typename Run>
void replay(const std::string& harness, Run run) {
  const std::vector<fs::path> files = corpus(harness);
  ASSERT_FALSE(files.empty()) << "no corpus in " << TIGHTEX_FUZZ_CORPUS << "/" << harness;
  for (const fs::path& f : files) {
    const std::string data = bytes_of(f);
    try {
      run(reinterpret_cast<const uint8_t*>(data.data()), data.size(), f.filename().string());
    } catch (const std::exception& e) {
      ADD_FAILURE() << f << ": neither read nor refused with an InputError: " << e.what();
    }
  }
}

TEST(FuzzCorpus, ObjReaderReadsOrRefuses) {
  replay("fuzz_obj", [](const uint8_t* d, size_t n, const std::string&) { tightex_fuzz::run_obj(d, n); });
}

TEST(FuzzCorpus, PlyReaderReadsOrRefuses) {
  replay("fuzz_ply", [](const uint8_t* d, size_t n, const std::string&) { tightex_fuzz::run_ply(d, n); });
}

TEST(FuzzCorpus, GltfReaderReadsOrRefusesAndWritesBack) {
  replay("fuzz_gltf", [](const uint8_t* d, size_t n, const std::string&) { tightex_fuzz::run_gltf(d, n); });
}

TEST(FuzzCorpus, ImageDecoderDecodesOrRefuses) {
  replay("fuzz_image", [](const uint8_t* d, size_t n, const std::string&) { tightex_fuzz::run_image(d, n); });
}

TEST(FuzzCorpus, PipelineLosesAndFlipsNothing) {
  replay("fuzz_pipeline", [](const uint8_t* d, size_t n, const std::string& name) {
    const tightex_fuzz::PipelineOutcome r = tightex_fuzz::run_pipeline(d, n);
    EXPECT_EQ(r.lost, 0u) << name;
    EXPECT_EQ(r.flipped, 0u) << name;
  });
}

// The seeds that are valid stay valid: a reader change that starts refusing them shows here.
TEST(FuzzCorpus, ValidSeedsAreAccepted) {
  for (const char* name : {"triangles.obj", "quad_normals.obj", "negative_indices.obj", "crlf.obj", "map_options.obj", "forward_refs.obj",
                           "mtllib_two.obj", "statements.obj", "windows_paths.obj"}) {
    const std::string data = bytes_of(fs::path(TIGHTEX_FUZZ_CORPUS) / "fuzz_obj" / name);
    EXPECT_EQ(tightex_fuzz::run_obj(reinterpret_cast<const uint8_t*>(data.data()), data.size()), Outcome::kAccepted) << name;
  }
  for (const char* name : {"ascii_two_pages.ply", "binary_le_vertex_st.ply", "binary_be_quads.ply", "every_type.ply", "windows_path.ply"}) {
    const std::string data = bytes_of(fs::path(TIGHTEX_FUZZ_CORPUS) / "fuzz_ply" / name);
    EXPECT_EQ(tightex_fuzz::run_ply(reinterpret_cast<const uint8_t*>(data.data()), data.size()), Outcome::kAccepted) << name;
  }
  for (const char* name :
       {"rgb8.png",    "rgba8.png",        "grey8.png",      "greyalpha8.png", "rgb16.png",       "rgba16.png", "grey16.png", "grey1.png",
        "palette.png", "palette_trns.png", "interlaced.png", "baseline.jpg",   "progressive.jpg", "grey.jpg",   "cmyk.jpg",   "rgb.bmp",
        "rgb.tga",     "rle.tga",          "small.gif",      "rgb.ppm",        "grey.pgm",        "rgb.psd"}) {
    const std::string data = bytes_of(fs::path(TIGHTEX_FUZZ_CORPUS) / "fuzz_image" / name);
    EXPECT_EQ(tightex_fuzz::run_image(reinterpret_cast<const uint8_t*>(data.data()), data.size()), Outcome::kAccepted) << name;
  }
}

}  // namespace
