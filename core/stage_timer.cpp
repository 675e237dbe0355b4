#include "core/stage_timer.hpp"

namespace ccd {

void StageTimes::add(std::string_view stage, double milliseconds) {
  for (auto& [name, ms] : entries_) {
    if (name == stage) {
      ms += milliseconds;
      return;
    }
  }
  entries_.emplace_back(std::string(stage), milliseconds);
}

double StageTimes::milliseconds(std::string_view stage) const {
  for (const auto& [name, ms] : entries_) {
    if (name == stage) return ms;
  }
  return 0.0;
}

double StageTimes::total_milliseconds() const {
  double total = 0.0;
  for (const auto& entry : entries_) total += entry.second;
  return total;
}

}  // namespace ccd
