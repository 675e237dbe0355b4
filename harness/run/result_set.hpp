#pragma once
/// @file
/// A result set of `run` read back, as `compare` and `check` read one: a `run --json` file (an array of summaries),
/// a run's `--out` folder (its results.jsonl) or a results.jsonl, every record read through its one reader once
/// (run/record_fields.hpp: FILE:WHERE: REASON, exit 2, never a raw type error).

#include "harness/run/record_fields.hpp"
#include "harness/run/records.hpp"

#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace ccd::harness {

/// An --out folder's log of every finished cell of every run into it (cell_store.hpp, ResultsLog), and the lock
/// that its writer holds while appending and a reader while reading.
inline constexpr const char* kResultsLogFile = "results.jsonl";
inline constexpr const char* kResultsLockFile = ".results.lock";

/// One side's records: the cells' summaries (one per cell: the latest, by finished_at, where an --out folder keeps
/// several runs' of one cell), and each cell's step records when the side has them.
struct ResultSet {
  std::filesystem::path path;
  std::vector<CellSummary> summaries;
  /// By steps_key: the step records of a cell, by step index.
  std::map<std::string, std::map<std::size_t, StepRecord>> steps;
  bool has_steps = false;
  /// Summaries that a later one of the same cell replaced (an --out folder keeps every run's).
  std::size_t replaced = 0;
};

/// A cell's steps are found by what both records name: scene, δ and resolved strategy.
std::string steps_key(const std::string& scene, double thickness, const std::string& strategy);

/// Reads `given`: an --out folder, a results.jsonl, or a `run --json` file, its summaries read for `use`.
/// @throws InputError for a file that is not a result set, a malformed record, or one with no summary at all.
ResultSet read_result_set(const std::filesystem::path& given, SummaryUse use = SummaryUse::compare);

/// The summaries of a `run --json` array (`file` names it in errors). @throws InputError.
std::vector<CellSummary> read_summaries(const nlohmann::json& document, const std::filesystem::path& file, SummaryUse use);

}  // namespace ccd::harness
