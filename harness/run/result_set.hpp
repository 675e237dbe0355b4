#pragma once
/// @file
/// A result set of `run` read back, as `compare` and `check` read one: a `run --json` file (an array of summaries),
/// a run's `--out` folder (its results.jsonl) or a results.jsonl, every field a reader reads checked first
/// (run/record_fields.hpp: FILE:WHERE: REASON, exit 2, never a raw type error).

#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace ccd::harness {

/// One side's records: the cells' summaries (one per cell: the latest, by finished_at, where an --out folder keeps
/// several runs' of one cell), and each cell's step records when the side has them.
struct ResultSet {
  std::filesystem::path path;
  std::vector<nlohmann::json> summaries;
  /// By steps_key: the step records of a cell, by step index.
  std::map<std::string, std::map<std::size_t, nlohmann::json>> steps;
  bool has_steps = false;
  /// Summaries that a later one of the same cell replaced (an --out folder keeps every run's).
  std::size_t replaced = 0;
};

/// A cell's steps are found by what both records name: scene, δ and resolved strategy.
std::string steps_key(const nlohmann::json& record);

/// Reads `given`: an --out folder, a results.jsonl, or a `run --json` file. @throws InputError for a file that is not
/// a result set, a malformed record, or one with no summary at all.
ResultSet read_result_set(const std::filesystem::path& given);

}  // namespace ccd::harness
