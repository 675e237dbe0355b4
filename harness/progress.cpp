#include "harness/progress.hpp"

#include <sys/ioctl.h>
#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace ccd::harness {
namespace {

/// On a terminal the bar is redrawn at most this often; in a log a line is written at most this often.
constexpr auto kTerminalInterval = std::chrono::milliseconds(100);
constexpr auto kLogInterval = std::chrono::milliseconds(1000);
/// Nothing is drawn during a command's first second: short commands stay quiet.
constexpr auto kQuietStart = std::chrono::seconds(1);
constexpr int kBarWidth = 24;

/// "1:05" (minutes:seconds), or "1:02:05" past an hour.
std::string clock_text(double seconds) {
  const long total = std::lround(std::max(0.0, seconds));
  char text[32];
  if (total >= 3600) {
    std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", total / 3600, total / 60 % 60, total % 60);
  } else {
    std::snprintf(text, sizeof text, "%ld:%02ld", total / 60, total % 60);
  }
  return text;
}

}  // namespace

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)), total_(total), terminal_(::isatty(STDERR_FILENO) == 1), start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(std::size_t done) { update(static_cast<double>(done), total_, detail_); }

void Progress::update(std::size_t done, std::size_t total) { update(static_cast<double>(done), total, detail_); }

void Progress::update(double done, std::size_t total, const std::string& detail) {
  done_ = done;
  total_ = total;
  detail_ = detail;
  const auto now = std::chrono::steady_clock::now();
  if (now - start_ < kQuietStart || now - last_ < (terminal_ ? kTerminalInterval : kLogInterval)) return;
  last_ = now;
  draw(false);
}

void Progress::line(const std::string& text) {
  if (bar_shown_) std::cerr << "\r\033[K";
  std::cerr << text << '\n';
  if (bar_shown_) draw(false);
}

void Progress::draw(bool final) {
  printed_ = true;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  // Built by appending: GCC 12 warns (-Wrestrict, wrongly) on "literal" + std::string chains here.
  std::string text = label_;
  text.append(": ").append(std::to_string(static_cast<std::size_t>(std::floor(done_))));
  if (total_ > 0) text.append("/").append(std::to_string(total_));
  text.append(", ").append(clock_text(elapsed)).append(" elapsed");
  if (final) {
    text.append(", done");
  } else if (total_ > 0 && done_ > 0) {
    text.append(", about ").append(clock_text(elapsed / done_ * (static_cast<double>(total_) - done_))).append(" left");
  }
  // Last, so that a narrow terminal cuts the detail and keeps the counts and the estimate.
  if (!detail_.empty() && !final) text.append(": ").append(detail_);
  if (!terminal_) {
    std::cerr << text << '\n';
    return;
  }
  const double fraction = total_ > 0 ? std::min(1.0, done_ / static_cast<double>(total_)) : 0.0;
  const int filled = static_cast<int>(fraction * kBarWidth);
  std::string bar(1, '[');
  bar.append(static_cast<std::size_t>(filled), '#').append(static_cast<std::size_t>(kBarWidth - filled), '-').append("] ").append(text);
  // One terminal line: a wrapped one would not be redrawn in place.
  winsize size{};
  const std::size_t columns = ::ioctl(STDERR_FILENO, TIOCGWINSZ, &size) == 0 && size.ws_col > 0 ? size.ws_col : 100;
  if (bar.size() >= columns) bar = bar.substr(0, columns - 1);
  std::cerr << "\r\033[K" << bar << (final ? "\n" : "") << std::flush;
  bar_shown_ = !final;
}

Progress::~Progress() {
  if (printed_) draw(true);
}

}  // namespace ccd::harness
