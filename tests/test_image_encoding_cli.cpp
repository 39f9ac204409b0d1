// Tests for the command line's texture encoding options on a small generated model: --png-level fast,
// the default (6) and 9 write smaller PNGs in that order with the same pixels; --jpeg-quality changes the JPEG; a bad
// value, or an option beside the other format, is refused with exit 1 and nothing written.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "mesh_catalogue.hpp"
#include "tightex/io.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;

class ImageEncodingCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / (std::string("tightex_encoding_cli_") +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    write_obj(testing::multi_component(), (dir_ / "in").string(), "multi", ImageFormat::kPng);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  /// Runs tightex on the model into dir_/OUT with `options`; its stderr goes to dir_/OUT.err. Returns
  /// the exit code (-1 if it did not exit).
  int run(const std::string& out, const std::string& options) const {
    const std::string cmd = std::string(TIGHTEX_CLI) + " '" + (dir_ / "in" / "multi.obj").string() + "' -o '" + (dir_ / out).string() +
                            "' --size 128 --no-html --quiet " + options + " 2> '" + (dir_ / (out + ".err")).string() + "'";
    const int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  std::string error_text(const std::string& out) const {
    std::ifstream f(dir_ / (out + ".err"));
    return std::string((std::istreambuf_iterator<char>(f)), {});
  }
  uintmax_t texture_bytes(const std::string& out, const std::string& extension) const {
    return fs::file_size(dir_ / out / ("multi_tightex" + extension));
  }

  fs::path dir_;
};

TEST_F(ImageEncodingCli, PngLevelsOrderTheirFilesAndDecodeToTheSamePixels) {
  ASSERT_EQ(run("fast", "--png-level fast"), 0);
  ASSERT_EQ(run("default", ""), 0);
  ASSERT_EQ(run("best", "--png-level 9"), 0);
  ASSERT_EQ(run("stored", "--png-level 0"), 0);
  EXPECT_LE(texture_bytes("best", ".png"), texture_bytes("default", ".png"));
  EXPECT_LT(texture_bytes("default", ".png"), texture_bytes("fast", ".png"));
  EXPECT_LT(texture_bytes("fast", ".png"), texture_bytes("stored", ".png"));
  const Image fast = load_image((dir_ / "fast" / "multi_tightex.png").string());
  for (const char* out : {"default", "best", "stored"}) {
    const Image other = load_image((dir_ / out / "multi_tightex.png").string());
    EXPECT_EQ(other.width, fast.width);
    EXPECT_EQ(other.height, fast.height);
    EXPECT_TRUE(other.pixels == fast.pixels) << out;
  }
}

TEST_F(ImageEncodingCli, JpegQualityChangesTheFile) {
  ASSERT_EQ(run("q92", "--format jpg --jpeg-quality 92"), 0);
  ASSERT_EQ(run("q30", "--format jpg --jpeg-quality 30"), 0);
  ASSERT_EQ(run("q100", "--format jpg --jpeg-quality 100"), 0);
  EXPECT_LT(texture_bytes("q30", ".jpg"), texture_bytes("q92", ".jpg"));
  EXPECT_LT(texture_bytes("q92", ".jpg"), texture_bytes("q100", ".jpg"));
}

TEST_F(ImageEncodingCli, BadValuesAreRefusedAndNothingIsWritten) {
  const struct {
    const char* options;
    const char* message;
  } cases[] = {
      {"--png-level 10", "--png-level"},
      {"--png-level -1", "--png-level"},
      {"--png-level quick", "--png-level"},
      {"--jpeg-quality 0", "--jpeg-quality"},
      {"--format jpg --jpeg-quality 101", "--jpeg-quality"},
      {"--format jpg --png-level 9", "--png-level needs --format png"},
      {"--jpeg-quality 80", "--jpeg-quality does nothing"},
      {"--webp-lossless", "--webp-lossless does nothing"},
      {"--format png --webp-quality 60", "--webp-quality needs --format webp"},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(run("bad", c.options), 1) << c.options;
    const std::string text = error_text("bad");
    const std::string first_line = text.substr(0, text.find('\n'));
    EXPECT_NE(first_line.find(c.message), std::string::npos) << c.options << ": " << text;
    EXPECT_FALSE(fs::exists(dir_ / "bad")) << c.options;
  }
}

}  // namespace
}  // namespace tightex
