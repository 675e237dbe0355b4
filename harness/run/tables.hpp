#pragma once
/// @file
/// What `ccdbench run` shows: the table of its cells (with speed-ups only between cells of this invocation,
/// docs/DESIGN.md §5) and the report page.

#include "harness/table.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace ccd::harness {

/// Sets each summary's "speedup" (its baseline's ms per step over its own) and "speedup_over" (the baseline's
/// resolved name), or null where it has none: the baseline is the first cell of its strategy's baseline strategy
/// (registry.hpp) on the same scene at the same δ with the same narrow phase, measured in this invocation on the
/// same rank and machine (docs/DESIGN.md §5: ratios only between cells of one invocation; resumed cells have none).
void attach_speedups(std::vector<nlohmann::json>& summaries);

/// One row per cell summary (speed-ups as attach_speedups set them).
Table summary_table(const std::vector<nlohmann::json>& summaries);

/// The resolved name of each strategy the table shows by its spec as given ("full = full+conservative:..."), "" when
/// every spec was given resolved.
std::string resolved_names(const std::vector<nlohmann::json>& summaries);

/// The footnotes `table` needs (what † means), "" when none.
std::string summary_notes(const Table& table);

/// The files write_report writes into its folder (a run removes them when it starts).
inline constexpr const char* kReportPage = "README.md";
inline constexpr const char* kReportSummaries = "summaries.json";
inline constexpr const char* kReportSteps = "steps.json";

/// Writes DIRECTORY/README.md (the table under the command that made it, the machine, the plots' names),
/// DIRECTORY/summaries.json and DIRECTORY/steps.json (every step record of `cells`), which scripts/plot_run.py
/// draws, atomically.
void write_report(const std::filesystem::path& directory, const Table& table, const std::vector<nlohmann::json>& summaries,
                  const std::vector<nlohmann::json>& cells, const std::string& command);

}  // namespace ccd::harness
