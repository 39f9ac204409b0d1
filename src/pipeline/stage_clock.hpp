// Each stage's wall time, the process's CPU time while it ran and the process's peak memory when it
// ended, for the report's "timings".
#pragma once
#include <chrono>
#include <vector>

#include "core/resources.hpp"
#include "report/report.hpp"

namespace tightex {

/// Times consecutive stages: each done() ends one and starts the next.
class StageClock {
 public:
  explicit StageClock(std::vector<StageTiming>& out) : out_(out), last_(std::chrono::steady_clock::now()), last_cpu_(process_cpu_times()) {}
  void done(const char* stage) {
    const auto now = std::chrono::steady_clock::now();
    const CpuTimes cpu = process_cpu_times();
    out_.push_back(
        {stage, std::chrono::duration<double>(now - last_).count(), peak_rss_mib(), cpu.user - last_cpu_.user, cpu.sys - last_cpu_.sys});
    last_ = now;
    last_cpu_ = cpu;
  }

 private:
  std::vector<StageTiming>& out_;
  std::chrono::steady_clock::time_point last_;
  CpuTimes last_cpu_;
};

}  // namespace tightex
