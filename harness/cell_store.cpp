#include "harness/cell_store.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/content_hash.hpp"
#include "datasets/input_file.hpp"
#include "harness/run/result_set.hpp"
#include "harness/truth_cache.hpp"
#include "strategies/registry.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <stdexcept>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace ccd::harness {
namespace {

using nlohmann::json;

constexpr int kCellFormat = 2;

std::string checksum_of(const json& cell_without_checksum) {
  const std::string text = cell_without_checksum.dump();
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(datasets::checksum64(text.data(), text.size())));
  return hex;
}

/// Parses and checks a cell file. @throws InputError when corrupt.
json load_cell(const std::filesystem::path& file) {
  json cell = datasets::read_json_file(file, "cell file");
  if (!cell.is_object() || !cell.contains("checksum") || !cell["checksum"].is_string()) {
    throw InputError(file, "checksum", "missing: not a cell file of this ccdbench");
  }
  const std::string stored = cell["checksum"].get<std::string>();
  cell.erase("checksum");
  if (checksum_of(cell) != stored) throw InputError(file, "checksum", "does not match the content (the file is corrupt)");
  for (const char* part : {"key", "summary", "steps"}) {
    if (!cell.contains(part)) throw InputError(file, part, "missing");
  }
  if (!cell["steps"].is_array() || !cell["summary"].is_object()) throw InputError(file, "steps", "malformed");
  return cell;
}

}  // namespace

json CellKey::to_json() const {
  return {{"format", kCellFormat}, {"scene", scene},         {"scene_content", scene_content},
          {"steps", steps},        {"thickness", thickness}, {"thickness_from", thickness_from},
          {"strategy", strategy},  {"verify", verify},       {"toi", toi},
          {"repeats", repeats},    {"threads", threads},     {"executable", executable}};
}

std::string scene_content_digest(const Scene& scene, std::span<const std::vector<Vec3>> frames) {
  datasets::ContentHash hash;
  hash.text("ccdbench scene content v1");
  hash_scene_structure(hash, scene);
  hash.value(static_cast<std::uint64_t>(frames.size()));
  for (const auto& frame : frames) hash.bytes(frame.data(), frame.size() * sizeof(Vec3));
  return hash.hex();
}

const std::string& executable_digest() {
  static const std::string digest = datasets::file_digest("/proc/self/exe");
  return digest;
}

std::string safe_path_component(const std::string& text) {
  std::string out;
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.' || c == '_' ? c : '_';
  if (out.empty() || out.find_first_not_of('.') == std::string::npos) out = "_" + out;
  return out;
}

std::string cell_file_name(const CellKey& key) {
  datasets::ContentHash hash;
  hash.text(key.to_json().dump());
  const std::string strategy_name = strategies::short_label(key.strategy);
  return safe_path_component(key.scene) + "__" + safe_path_component(strategy_name) + "_" + hash.hex().substr(0, 20) + ".json";
}

std::optional<json> read_cell(const std::filesystem::path& file, const CellKey& key) {
  if (!std::filesystem::exists(file)) return std::nullopt;
  json cell = load_cell(file);
  if (cell["key"] != key.to_json()) return std::nullopt;
  return cell;
}

void write_cell(const std::filesystem::path& file, json cell) {
  cell.erase("checksum");
  cell["checksum"] = checksum_of(cell);
  datasets::AtomicFile out(file, std::ios::out);
  out.stream() << cell.dump() << '\n';
  out.commit();
}

namespace {

std::string finished_at_of(const json& cell) {
  const json& summary = cell["summary"];
  return summary.contains("finished_at") && summary["finished_at"].is_string() ? summary["finished_at"].get<std::string>() : "";
}

/// What a reader of the log takes a cell's latest lines by: its scene, δ and strategy, the reader's own key.
std::string reader_key(const json& cell) {
  const json& summary = cell["summary"];
  return steps_key(summary.value("scene", std::string()), summary.value("thickness", 0.0), summary.value("strategy", std::string()));
}

/// A cell's lines in the log: its step records, then its summary.
std::string log_lines(const json& cell) {
  std::string text;
  for (const json& step : cell["steps"]) text += step.dump() + '\n';
  return text + cell["summary"].dump() + '\n';
}

ResultsLog::FileState state_of(const struct ::stat& info) {
  return ResultsLog::FileState{static_cast<unsigned long long>(info.st_ino), static_cast<unsigned long long>(info.st_size),
                               static_cast<long long>(info.st_mtim.tv_sec) * 1000000000LL + info.st_mtim.tv_nsec};
}

std::optional<ResultsLog::FileState> state_of(const std::filesystem::path& file) {
  struct ::stat info {};
  if (::stat(file.c_str(), &info) != 0) return std::nullopt;
  return state_of(info);
}

/// Appends `text` to `file` in one piece: a write that fails part-way (a full disk) is cut back off, so the file
/// never ends in half a line that this process could have taken back. @returns the file's state after it.
ResultsLog::FileState append_whole(const std::filesystem::path& file, const std::string& text) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(file.string() + ": cannot be opened to append: " + std::strerror(errno));
  struct ::stat before {};
  if (::fstat(fd, &before) != 0) {
    const int error = errno;
    ::close(fd);
    throw std::runtime_error(file.string() + ": cannot be read before appending: " + std::strerror(error));
  }
  std::size_t done = 0;
  while (done < text.size()) {
    const ::ssize_t wrote = ::write(fd, text.data() + done, text.size() - done);
    if (wrote < 0 && errno == EINTR) continue;
    if (wrote <= 0) {
      const int error = wrote == 0 ? ENOSPC : errno;  // a write of nothing sets no errno
      [[maybe_unused]] const int cut = ::ftruncate(fd, before.st_size);
      ::close(fd);
      throw std::runtime_error(file.string() + ": a cell's lines could not be appended: " + std::strerror(error));
    }
    done += static_cast<std::size_t>(wrote);
  }
  struct ::stat after {};
  ::fstat(fd, &after);
  ::close(fd);
  return state_of(after);
}

}  // namespace

void ResultsLog::add(const std::filesystem::path& file, const json& cell, std::ostream& warnings) {
  const datasets::FileLock lock(out_ / kResultsLockFile);
  const std::filesystem::path log = out_ / kResultsLogFile;
  const std::string name = file.filename().string();
  const std::string finished = finished_at_of(cell);
  const std::string key = reader_key(cell);
  // A reader takes a cell's summary by the latest finished_at among those of its scene, δ and strategy, and its steps
  // by the last lines: a cell that finished before another of its key already in the log goes in its place (a
  // rebuild). Cells of other keys may come in any order (under MPI they reach rank 0 out of order).
  const auto latest = latest_.find(key);
  if (!written_ || state_of(log) != written_ || (latest != latest_.end() && finished < latest->second)) {
    rebuild(warnings);
    return;
  }
  // A cell computed again: its earlier lines stay until the run's end (every reader takes a cell's latest summary and
  // steps), so that a rerun of a whole sweep with --fresh does not rebuild the log after each cell.
  if (names_.count(name) != 0) stale_ = true;
  written_ = append_whole(log, log_lines(cell));
  names_.insert(name);
  latest_[key] = finished;
}

void ResultsLog::finish(std::ostream& warnings) {
  const std::filesystem::path log = out_ / kResultsLogFile;
  if (!written_ && !std::filesystem::exists(log)) return;  // nothing to repair, and a run that finished no cell writes none
  const datasets::FileLock lock(out_ / kResultsLockFile);
  if (!written_ || stale_ || state_of(log) != written_) rebuild(warnings);
}

void ResultsLog::rebuild(std::ostream& warnings) {
  struct Finished {
    std::string finished_at;
    std::string name;
    json cell;
  };
  std::vector<Finished> cells;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(out_ / "cells", error)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || entry.path().extension() != ".json" || name.find(".tmp.") != std::string::npos) continue;
    try {
      json cell = load_cell(entry.path());
      std::string finished = finished_at_of(cell);
      cells.push_back({std::move(finished), name, std::move(cell)});
    } catch (const InputError& bad) {
      warnings << "ccdbench: warning: " << bad.what() << "; left out of results.jsonl\n";
    }
  }
  std::sort(cells.begin(), cells.end(),
            [](const Finished& a, const Finished& b) { return std::tie(a.finished_at, a.name) < std::tie(b.finished_at, b.name); });
  const std::filesystem::path log = out_ / kResultsLogFile;
  // Until the new log is in place, this run knows nothing of it: a failed commit leaves no state to append after.
  written_.reset();
  names_.clear();
  latest_.clear();
  stale_ = false;
  datasets::AtomicFile lines(log, std::ios::out);
  for (const Finished& finished : cells) {
    lines.stream() << log_lines(finished.cell);
    names_.insert(finished.name);
    std::string& latest = latest_[reader_key(finished.cell)];
    latest = std::max(latest, finished.finished_at);
  }
  lines.commit();
  written_ = state_of(log);
}

}  // namespace ccd::harness
