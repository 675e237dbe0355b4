#pragma once
/// @file
/// Progress lines on stderr for long runs: rate-limited, so short runs print nothing.

#include <chrono>
#include <string>

namespace ccd::harness {

/// Reports "LABEL: done/total" on stderr at most twice a second, starting only after the first second.
class Progress {
 public:
  Progress(std::string label, std::size_t total);
  /// Marks `done` items finished (prints when due).
  void update(std::size_t done);
  /// The same, for work whose total is known only once it starts.
  void update(std::size_t done, std::size_t total);
  /// Prints the final count if anything was printed before.
  ~Progress();

 private:
  std::string label_;
  std::size_t total_;
  std::size_t done_ = 0;
  bool printed_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace ccd::harness
