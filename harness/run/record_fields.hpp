#pragma once
/// @file
/// Reading a record of `run` back from a file, as a reader (`check`, `compare`) takes it: each field a reader reads
/// is checked to be of its kind, then the record is read by its one reader (run/records.hpp). A record that is not so
/// is bad input (FILE:WHERE: REASON, exit 2), found before anything is judged or written, never a raw type error nor
/// a verdict.

#include "harness/run/records.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace ccd::harness {

/// What a summary is read for: the gate needs a cell's identity and its verdict's counts; compare also its steps and
/// time.
enum class SummaryUse { gate, compare };

/// A summary read back from `file` (`where` names it there: "entry 3", "line 12"). @throws InputError(file,
/// WHERE.FIELD, "must be ..., got VALUE"), or (file, where, ...) for a missing field, a record that is not an object or
/// that its reader refuses.
CellSummary read_summary(const nlohmann::json& record, const std::filesystem::path& file, const std::string& where, SummaryUse use);

/// A step record read back, its kept missed pairs checked too (their kind, ids and 24 finite coordinates).
/// @throws InputError as read_summary.
StepRecord read_step_record(const nlohmann::json& record, const std::filesystem::path& file, const std::string& where);

/// A cell file's record (its checksum checked by the cell store), read. @throws InputError as read_summary.
CellRecord read_cell_record(const nlohmann::json& cell, const std::filesystem::path& file);

}  // namespace ccd::harness
