#pragma once
/// @file
/// Progress of long commands on stderr: on a terminal, one line redrawn in place with a bar, the count, what is under
/// way and an estimate of the time left; otherwise (a log, a pipe) plain lines, rate-limited, so short runs print
/// nothing but the lines they are asked to print.

#include <chrono>
#include <string>

namespace ccd::harness {

class Progress {
 public:
  /// `label` leads every line ("run: cells"); `total` items (0: not known yet).
  Progress(std::string label, std::size_t total);
  /// Marks `done` items finished (prints when due).
  void update(std::size_t done);
  /// The same, for work whose total is known only once it starts.
  void update(std::size_t done, std::size_t total);
  /// `done` may be part-way through an item (the estimate uses it); `detail` says what is under way.
  void update(double done, std::size_t total, const std::string& detail);
  /// Prints `text` as a line of its own (above the bar on a terminal).
  void line(const std::string& text);
  /// Whether stderr is a terminal (then a bar, else plain lines).
  bool terminal() const { return terminal_; }
  /// Ends the bar (or prints the final count if anything was printed before).
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

 private:
  void draw(bool final);
  std::string label_;
  std::size_t total_;
  double done_ = 0;
  std::string detail_;
  bool terminal_;
  bool printed_ = false;
  bool bar_shown_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace ccd::harness
