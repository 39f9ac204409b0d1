// Shared by the libFuzzer harnesses: a private scratch folder per process, one TBB thread (the
// harnesses must be deterministic for libFuzzer's coverage feedback, and the machine they run on is
// shared), and a record of inputs that did not crash but broke a promise (an InternalError, a lost or
// flipped triangle), so a long run keeps going while every such input is kept for a regression test.
#pragma once
#include <tbb/global_control.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <string>
#include <string_view>

namespace tightex_fuzz {

namespace fs = std::filesystem;

/// Runs one input; an exception that escapes is a finding: libFuzzer sees an abort and keeps the input.
template <typename Run>
void or_abort(const char* harness, Run&& run) {
  try {
    run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: unexpected exception: %s\n", harness, e.what());
    std::abort();
  }
}

inline void limit_threads() { static tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1); }

/// A folder of its own for this process, on /dev/shm when there is one (every run writes files),
/// removed at exit.
inline const fs::path& scratch_dir(const std::string& harness) {
  static const fs::path dir = [&] {
    std::error_code ec;
    const fs::path base = fs::is_directory("/dev/shm", ec) ? fs::path("/dev/shm") : fs::temp_directory_path();
    fs::path d = base / ("tightex_" + harness + "_" + std::to_string(::getpid()));
    fs::remove_all(d, ec);
    fs::create_directories(d);
    return d;
  }();
  static const bool cleanup_registered = [] {
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(dir, ec);
    });
    return true;
  }();
  (void)cleanup_registered;
  return dir;
}

inline void write_file(const fs::path& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

/// An input that broke a promise without crashing. Set TIGHTEX_FUZZ_STRICT=1 to abort instead (then
/// libFuzzer stops and writes the input as a crash); otherwise the first input of each kind of
/// message is written to $TIGHTEX_FUZZ_FINDINGS (default ./fuzz-findings) and the run goes on.
inline void finding(const std::string& kind, const std::string& message, const uint8_t* data, size_t size) {
  if (const char* strict = std::getenv("TIGHTEX_FUZZ_STRICT"); strict != nullptr && std::string(strict) == "1") {
    std::fprintf(stderr, "FINDING %s: %s\n", kind.c_str(), message.c_str());
    std::abort();
  }
  // One file per distinct message with its digits removed ("triangle 3" and "triangle 7" are one kind).
  std::string key = kind + ":";
  for (char c : message)
    if (c < '0' || c > '9') key += c;
  static std::set<std::string> seen;
  if (!seen.insert(key).second) return;
  const char* env = std::getenv("TIGHTEX_FUZZ_FINDINGS");
  const fs::path dir = env != nullptr ? fs::path(env) : fs::path("fuzz-findings");
  std::error_code ec;
  fs::create_directories(dir, ec);
  uint64_t hash = 1469598103934665603ull;  // FNV-1a of the input names the file
  for (size_t i = 0; i < size; ++i) hash = (hash ^ data[i]) * 1099511628211ull;
  char name[64];
  std::snprintf(name, sizeof name, "%s-%016llx", kind.c_str(), static_cast<unsigned long long>(hash));
  write_file(dir / name, std::string_view(reinterpret_cast<const char*>(data), size));
  std::fprintf(stderr, "FINDING %s (%s): %s\n", kind.c_str(), (dir / name).c_str(), message.c_str());
}

}  // namespace tightex_fuzz
