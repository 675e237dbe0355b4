#pragma once
/// @file
/// What the harness times is the strategy's work alone (issue 36): from the frames in memory to its answers handed
/// over. `TimedRegion` marks that span (run_cell's step call, queries' answer loop); every harness-side pass
/// (verification, the answers' digest, fault and answer files, scoring) announces itself with `harness_pass`, which
/// records it when it finds itself inside a timed region. A test runs cells and queries and requires none: moving
/// a harness pass into a strategy's time fails it.

#include <string>
#include <vector>

namespace ccd::harness {

/// Marks a strategy's timed span while it lives (not nested, not copied).
class TimedRegion {
 public:
  TimedRegion();
  ~TimedRegion();
  TimedRegion(const TimedRegion&) = delete;
  TimedRegion& operator=(const TimedRegion&) = delete;
};

/// Announces a harness-side pass: recorded (by name) when called inside a TimedRegion, from any thread.
void harness_pass(const char* name);

/// The passes recorded inside a timed region since the last clear, in order, and how many passes were announced
/// in all (inside or not: a test shows with it that the passes it guards ran).
std::vector<std::string> harness_passes_in_timed_region();
std::size_t harness_passes_announced();
void clear_harness_passes_in_timed_region();

}  // namespace ccd::harness
