#pragma once
/// @file
/// What `ccdbench run` shows: the table of its cells (with speed-ups only between cells of this invocation,
/// DESIGN.md §5) and the report page.

#include "harness/table.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace ccd::harness {

/// One row per cell summary; the speed-up of a cell is its strategy's baseline's time (registry.hpp: the first
/// cell of that strategy on the same scene with the same narrow phase, on the same rank and machine, not resumed)
/// over its own.
Table summary_table(const std::vector<nlohmann::json>& summaries);

/// The footnotes `table` needs (what † means), "" when none.
std::string summary_notes(const Table& table);

/// Writes DIRECTORY/README.md (the table under the command that made it, the machine, the plots' names) and
/// DIRECTORY/steps.json (every step record of `cells`, which scripts/plot_run.py draws), atomically.
void write_report(const std::filesystem::path& directory, const Table& table, const std::vector<nlohmann::json>& cells,
                  const std::string& command);

}  // namespace ccd::harness
