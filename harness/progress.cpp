#include "harness/progress.hpp"

#include <iostream>

namespace ccd::harness {

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)), total_(total), start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(std::size_t done) {
  done_ = done;
  const auto now = std::chrono::steady_clock::now();
  if (now - start_ < std::chrono::seconds(1) || now - last_ < std::chrono::milliseconds(500)) return;
  last_ = now;
  printed_ = true;
  std::cerr << label_ << ": " << done_ << "/" << total_ << '\n';
}

void Progress::update(std::size_t done, std::size_t total) {
  total_ = total;
  update(done);
}

Progress::~Progress() {
  if (printed_) std::cerr << label_ << ": " << done_ << "/" << total_ << " done\n";
}

}  // namespace ccd::harness
