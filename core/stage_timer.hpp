#pragma once
/// @file
/// Per-stage wall-clock times of one step ("refit", "traversal", "narrow phase"...).

#include <chrono>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ccd {

/// Milliseconds per named stage, in the order stages first appeared; a stage timed twice accumulates.
class StageTimes {
 public:
  void add(std::string_view stage, double milliseconds);
  /// 0 for a stage never timed.
  double milliseconds(std::string_view stage) const;
  double total_milliseconds() const;
  const std::vector<std::pair<std::string, double>>& entries() const { return entries_; }

 private:
  std::vector<std::pair<std::string, double>> entries_;
};

/// Adds the time from construction to destruction to `times` under `stage` (a name that outlives the timer,
/// normally a literal). Uses the steady clock.
class ScopedStageTimer {
 public:
  ScopedStageTimer(StageTimes& times, std::string_view stage) : times_(times), stage_(stage), start_(std::chrono::steady_clock::now()) {}
  ScopedStageTimer(const ScopedStageTimer&) = delete;
  ScopedStageTimer& operator=(const ScopedStageTimer&) = delete;
  ~ScopedStageTimer() {
    const std::chrono::duration<double, std::milli> elapsed = std::chrono::steady_clock::now() - start_;
    times_.add(stage_, elapsed.count());
  }

 private:
  StageTimes& times_;
  std::string_view stage_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace ccd
