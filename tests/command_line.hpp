// What the tests that run the `tightex` command share: a scratch folder of their own, whole files in
// and out, and the command's exit status.
#pragma once
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

#include <gtest/gtest.h>

namespace tightex::testing {

/// The scratch folders this process made, removed when it exits unless one of its tests failed (then
/// they are kept to look at). Each test runs in a process of its own (gtest_discover_tests).
class ScratchFolders {
 public:
  void add(const std::filesystem::path& folder) { folders_.push_back(folder); }
  ~ScratchFolders() {
    if (::testing::UnitTest::GetInstance()->failed_test_count() > 0) return;
    std::error_code ignored;
    for (const std::filesystem::path& folder : folders_) std::filesystem::remove_all(folder, ignored);
  }

 private:
  std::vector<std::filesystem::path> folders_;
};

/// An empty folder under the system's temporary folder, named for the test and this process (test
/// shards run side by side), removed when the process exits.
inline std::filesystem::path scratch_folder(const std::string& name) {
  static ScratchFolders made;
  const std::filesystem::path d = std::filesystem::temp_directory_path() / ("tightex_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  made.add(d);
  return d;
}

inline void write_whole(const std::filesystem::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

inline std::string read_whole(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// Runs `tightex ARGS` through the shell; its exit status (-1 when a signal ended it).
inline int run_tightex(const std::string& args) {
  std::string command = TIGHTEX_CLI;
  command += ' ';
  command += args;
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace tightex::testing
