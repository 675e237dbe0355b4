#include "harness/cell_store.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/content_hash.hpp"
#include "datasets/input_file.hpp"
#include "harness/truth_cache.hpp"
#include "strategies/registry.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <ostream>

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

void rebuild_results_log(const std::filesystem::path& out, std::ostream& warnings) {
  const datasets::FileLock lock(out / ".results.lock");
  struct Finished {
    std::string finished_at;
    std::string name;
    json cell;
  };
  std::vector<Finished> cells;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(out / "cells", error)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || entry.path().extension() != ".json" || name.find(".tmp.") != std::string::npos) continue;
    try {
      json cell = load_cell(entry.path());
      const json& summary = cell["summary"];
      std::string finished = summary.contains("finished_at") && summary["finished_at"].is_string() ? summary["finished_at"].get<std::string>() : "";
      cells.push_back({std::move(finished), name, std::move(cell)});
    } catch (const InputError& bad) {
      warnings << "ccdbench: warning: " << bad.what() << "; left out of results.jsonl\n";
    }
  }
  std::sort(cells.begin(), cells.end(),
            [](const Finished& a, const Finished& b) { return std::tie(a.finished_at, a.name) < std::tie(b.finished_at, b.name); });
  datasets::AtomicFile lines(out / "results.jsonl", std::ios::out);
  for (const Finished& finished : cells) {
    for (const json& step : finished.cell["steps"]) lines.stream() << step.dump() << '\n';
    lines.stream() << finished.cell["summary"].dump() << '\n';
  }
  lines.commit();
}

}  // namespace ccd::harness
