#include "harness/timed_region.hpp"

#include <atomic>
#include <mutex>

namespace ccd::harness {
namespace {

// Process-wide (a strategy's tasks run on any thread): the harness times one strategy call at a time.
std::atomic<int> open_regions{0};
std::atomic<std::size_t> announced{0};
std::mutex recorded_mutex;
std::vector<std::string>& recorded() {
  static std::vector<std::string> names;
  return names;
}

}  // namespace

TimedRegion::TimedRegion() { open_regions.fetch_add(1, std::memory_order_relaxed); }
TimedRegion::~TimedRegion() { open_regions.fetch_sub(1, std::memory_order_relaxed); }

void harness_pass(const char* name) {
  announced.fetch_add(1, std::memory_order_relaxed);
  if (open_regions.load(std::memory_order_relaxed) == 0) return;
  const std::lock_guard<std::mutex> lock(recorded_mutex);
  recorded().emplace_back(name);
}

std::vector<std::string> harness_passes_in_timed_region() {
  const std::lock_guard<std::mutex> lock(recorded_mutex);
  return recorded();
}

std::size_t harness_passes_announced() { return announced.load(std::memory_order_relaxed); }

void clear_harness_passes_in_timed_region() {
  const std::lock_guard<std::mutex> lock(recorded_mutex);
  recorded().clear();
  announced.store(0, std::memory_order_relaxed);
}

}  // namespace ccd::harness
