#pragma once
/// @file
/// What `ccdbench run` shows, as reporters over its result (RunResult, run/records.hpp): the table of its cells (with
/// speed-ups only between cells of this invocation, docs/DESIGN.md §5), --json, and the report page.

#include "harness/run/options.hpp"
#include "harness/run/records.hpp"
#include "harness/table.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace ccd::harness {

/// Sets each summary's speed-up (its baseline's ms per step over its own) and the baseline's resolved name, or none
/// where it has none: the baseline is the first cell of its strategy's baseline strategy (registry.hpp) on the same
/// scene at the same δ with the same narrow phase, measured in this invocation on the same rank and machine
/// (docs/DESIGN.md §5: ratios only between cells of one invocation; resumed cells have none).
void attach_speedups(std::vector<CellRecord>& cells);

/// One row per cell (speed-ups as attach_speedups set them).
Table summary_table(const std::vector<CellRecord>& cells);

/// The resolved name of each strategy the table shows by its spec as given ("full = full+conservative:..."), "" when
/// every spec was given resolved.
std::string resolved_names(const std::vector<CellRecord>& cells);

/// The footnotes `table` needs (what † means), "" when none.
std::string summary_notes(const Table& table);

/// The summaries as --json writes them: an array, each through the one serializer (run/records.hpp).
nlohmann::json summaries_json(const std::vector<CellRecord>& cells);

/// The files write_report writes into its folder (a run removes them when it starts).
inline constexpr const char* kReportPage = "README.md";
inline constexpr const char* kReportSummaries = "summaries.json";
inline constexpr const char* kReportSteps = "steps.json";

/// Writes DIRECTORY/README.md (the table under the command that made it, the machine, the plots' names),
/// DIRECTORY/summaries.json and DIRECTORY/steps.json (every step record of `cells`), which scripts/plot_run.py
/// draws, atomically.
void write_report(const std::filesystem::path& directory, const Table& table, const std::vector<CellRecord>& cells, const std::string& command);

/// `ccdbench run`'s reporters over its result: prints the table, its notes, the cells' errors and the cells left out
/// on `out`, and writes --json and --report where the options ask (rank 0 only: other ranks' results are empty).
void report_run(const RunResult& result, const RunOptions& options, std::ostream& out);

}  // namespace ccd::harness
