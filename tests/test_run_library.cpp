// The library's whole run (tightex/run.hpp) as a caller sees it: progress through the last file renamed
// into place, a cancel at a late stage leaving nothing written, and the same bytes as the command.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "command_line.hpp"
#include "mesh_catalogue.hpp"
#include "tightex/io.hpp"
#include "tightex/run.hpp"

namespace tightex {
namespace {

namespace fs = std::filesystem;

/// The catalogue's sphere with a 128^2 texture of gradients, written as OBJ + PNG into `dir`; its path.
fs::path sphere_obj(const fs::path& dir) {
  TexturedMesh m = testing::sphere();
  Image img(128, 128);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) img.at(x, y) = {uint8_t(2 * x), uint8_t(x * y / 64), uint8_t(255 - 2 * y), 255};
  m.textures[0].image = img;
  m.textures[0].path = "sphere_texture";
  write_obj(m, dir.string(), "sphere", ImageEncoding(ImageFormat::kPng));
  return dir / "sphere.obj";
}

/// The files a run writes into `dir` (none where it does not exist), by name.
std::vector<std::string> sorted_files_in(const fs::path& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) names.push_back(e.path().filename().string());
  return names;
}

struct Event {
  std::string stage;
  double fraction;
  size_t files;  // in the output folder when the event came
};

TEST(RunLibrary, LastProgressEventComesAfterEveryFileIsInPlace) {
  const fs::path dir = testing::scratch_folder("run_progress");
  const fs::path in = sphere_obj(dir / "in"), out = dir / "out";
  std::vector<Event> events;
  Options options;
  options.size = 128;
  options.progress = [&](std::string_view stage, double fraction) {
    events.push_back({std::string(stage), fraction, sorted_files_in(out).size()});
    return true;
  };
  const Report report = run(in.string(), out.string(), options);
  const std::vector<std::string> written = sorted_files_in(out);
  // The model, its material, its texture, report.json and report.html.
  ASSERT_EQ(written.size(), 5u);
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().stage, "done");
  EXPECT_EQ(events.back().fraction, 1.0);
  EXPECT_EQ(events.back().files, written.size());
  // "done" once, last; the run's own stages in order, nothing written before "write"; the measure reads
  // the model as written (its three files), the reports come last.
  std::vector<std::string> stages;
  for (const Event& e : events)
    if (stages.empty() || stages.back() != e.stage) stages.push_back(e.stage);
  EXPECT_EQ(std::count(stages.begin(), stages.end(), "done"), 1);
  const auto at = [&](const char* s) { return std::find(stages.begin(), stages.end(), s) - stages.begin(); };
  EXPECT_EQ(at("read"), 0);
  EXPECT_LT(at("read"), at("repair"));
  EXPECT_LT(at("bake"), at("encode"));
  EXPECT_LT(at("encode"), at("write"));
  EXPECT_LT(at("write"), at("measure"));
  EXPECT_LT(at("measure"), at("done"));
  for (size_t i = 0; i < events.size(); ++i) {
    if (events[i].stage == "measure")
      EXPECT_EQ(events[i].files, 3u);
    else if (events[i].stage != "done")
      EXPECT_EQ(events[i].files, 0u) << events[i].stage;
    if (i > 0 && events[i].stage == events[i - 1].stage) EXPECT_GE(events[i].fraction, events[i - 1].fraction) << events[i].stage;
  }
}

/// Runs with a progress callback that cancels at the first event of `stage` whose fraction is at least
/// `from`; expects Cancelled and no file in the output folder.
void expect_cancel_leaves_nothing(const std::string& stage, double from, const std::string& format = "") {
  SCOPED_TRACE(stage);
  const fs::path dir = testing::scratch_folder("run_cancel_" + stage);
  const fs::path in = sphere_obj(dir / "in"), out = dir / "out";
  Options options;
  options.size = 128;
  if (!format.empty()) {
    options.texture_format = ImageFormat::kWebp;
    options.target_psnr_db = 30;
  }
  bool asked = false;
  options.progress = [&](std::string_view s, double fraction) {
    asked = asked || (s == stage && fraction >= from);
    return !asked;
  };
  EXPECT_THROW(run(in.string(), out.string(), options), Cancelled);
  EXPECT_TRUE(asked);
  EXPECT_EQ(sorted_files_in(out), std::vector<std::string>{});
}

TEST(RunLibrary, CancelAtALateStageLeavesNoFile) {
  expect_cancel_leaves_nothing("read", 0);
  expect_cancel_leaves_nothing("encode", 0);
  expect_cancel_leaves_nothing("measure", 0);
  expect_cancel_leaves_nothing("write", 0);
  // Inside --target-psnr's search: rate control's encodings and the smaller budgets' plans and bakes.
  expect_cancel_leaves_nothing("encode", 0.05, "webp");
  expect_cancel_leaves_nothing("encode", 0.5, "webp");
}

TEST(RunLibrary, LibraryAndCommandWriteTheSameBytes) {
  const fs::path dir = testing::scratch_folder("run_same_bytes");
  const fs::path in = sphere_obj(dir / "in");
  // --size means a square to both: the library's Options::size as the command's --size.
  ASSERT_EQ(testing::run_tightex("'" + in.string() + "' -o '" + (dir / "command").string() + "' --quiet --size 96"), 0);
  Options options;
  options.size = 96;
  run(in.string(), (dir / "library").string(), options);
  const std::vector<std::string> names = sorted_files_in(dir / "command");
  EXPECT_EQ(sorted_files_in(dir / "library").size(), names.size());
  size_t compared = 0;
  for (const std::string& name : names) {
    if (name == "report.json" || name == "report.html") continue;  // their times differ
    EXPECT_EQ(testing::read_whole(dir / "command" / name), testing::read_whole(dir / "library" / name)) << name;
    ++compared;
  }
  EXPECT_EQ(compared, 3u);  // sphere.obj, sphere.mtl, the texture
}

}  // namespace
}  // namespace tightex
