// Progress of a stage whose work is done by many threads: each adds the units it finished; the
// caller's callback hears the fraction done from whichever thread finished, one call at a time, never
// going backwards, at most every `interval_s` (the first report comes at once).
#pragma once
#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>

#include "tightex/error.hpp"
#include "tightex/options.hpp"

namespace tightex {

class ProgressCounter {
 public:
  ProgressCounter(std::function<void(double)> report, double total_units, double interval_s = 0.2)
      : report_(std::move(report)), total_(total_units), interval_(interval_s) {}

  /// The total, where it is known only once the counter has been handed out (before any advance).
  void set_total(double total_units) { total_ = total_units; }
  void advance(double units) {
    done_.fetch_add(units);
    if (!report_ || !(total_ > 0)) return;
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;  // another thread is reporting
    const auto now = std::chrono::steady_clock::now();
    if (reported_once_ && now - last_ < interval_) return;
    reported_once_ = true;
    last_ = now;
    // Read under the lock: a value read before it could be older than one another thread has
    // reported meanwhile.
    report_(std::clamp(done_.load() / total_, 0.0, 1.0));
  }

 private:
  std::function<void(double)> report_;
  double total_;
  std::chrono::duration<double> interval_;
  std::atomic<double> done_{0};
  std::mutex mutex_;
  std::chrono::steady_clock::time_point last_{};
  bool reported_once_ = false;
};

/// The caller's progress callback (Options::progress) as the stages call it: a call that the callback
/// answers with false throws Cancelled, naming the stage.
class StageProgress {
 public:
  explicit StageProgress(const ProgressCallback& callback) : callback_(callback) {}
  void operator()(std::string_view stage, double fraction) const {
    if (callback_ && !callback_(stage, fraction)) throw Cancelled("cancelled during " + std::string(stage));
  }
  /// The fraction-only report of one stage (ProgressCounter, the bake), or empty without a callback.
  std::function<void(double)> of_stage(const char* stage) const {
    if (!callback_) return nullptr;
    return [this, stage](double fraction) { (*this)(stage, fraction); };
  }

 private:
  const ProgressCallback& callback_;
};

}  // namespace tightex
