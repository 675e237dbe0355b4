#pragma once
/// @file
/// `ccdbench queries`: every method on every query file, scored against the files' labels (docs/running.md).

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace ccd::harness {

struct QueriesOptions {
  std::vector<std::filesystem::path> paths;
  std::vector<std::string> methods{"exact"};
  double thickness = 0.0;
  int repeats = 1;
  std::optional<std::filesystem::path> json;
  /// Vary each narrow phase's accuracy parameter (see sweep_methods).
  bool sweep = false;
  /// Also score the extremes suite (labelled by the reference at zero thickness) as one more data set.
  bool extremes = false;
  /// Score files without truth labels (their FN and FP are unknown, shown as '-'); otherwise such a file is an error.
  bool allow_unlabelled = false;
  /// Compare TOIs with the exact earliest contact.
  bool toi = false;
  /// Rescale every query (and δ) by 2^scale_exponent first.
  int scale_exponent = 0;
  /// Write README.md and scores.json into this folder, with `command_line` above the table.
  std::optional<std::filesystem::path> report;
  /// Write every method's answers as an answer file (answer_files.hpp).
  std::optional<std::filesystem::path> write_answers;
  /// Where queries without an answer (faults) are written as query files.
  std::filesystem::path faults = "ccdbench-faults";
  std::string command_line;
};
/// Scores every method on every discovered query file; prints a table. Exit status 0.
int run_queries(const QueriesOptions& options, std::ostream& out);

}  // namespace ccd::harness
