// Each stage's wall time and the process's peak memory when it ended, for the report's "timings".
#pragma once
#include <chrono>
#include <vector>

#include "core/resources.hpp"
#include "report/report.hpp"

namespace tightex {

class StageClock {
 public:
  explicit StageClock(std::vector<StageTiming>& out) : out_(out), last_(std::chrono::steady_clock::now()) {}
  void done(const char* stage) {
    const auto now = std::chrono::steady_clock::now();
    out_.push_back({stage, std::chrono::duration<double>(now - last_).count(), peak_rss_mib()});
    last_ = now;
  }

 private:
  std::vector<StageTiming>& out_;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace tightex
