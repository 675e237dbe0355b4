#pragma once
/// @file
/// `ccdbench compare BASE HEAD`: two result sets of `run` (docs/ci-regression.md), cell by cell. Cells are matched
/// as the gate matches them (scene, δ, the strategy as given), or by `--pair BASE_SPEC=HEAD_SPEC` (two builds of a
/// plugin in one run). Per cell it shows missed, errors, false alarms, late TOIs, the TOI error's percentiles, memory,
/// and ms per step with the ratio and whether it is beyond the noise of the repeats (a Mann-Whitney U test over each
/// pass's time, harness/rank_test.hpp); with step records (an --out folder or results.jsonl) also the steps whose
/// answers digests changed and the pairs the head newly misses, which it writes as query files to replay. Verdicts
/// are compared only between cells of the same input and times only between records made alike
/// (run/comparability.hpp).

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace ccd::harness {

struct CompareOptions {
  /// Each an --out folder (its results.jsonl), a results.jsonl file, or a `run --json` file of summaries.
  std::filesystem::path base, head;
  /// Cells of BASE_SPEC on the base side matched with cells of HEAD_SPEC on the head side (both sides may then be one
  /// run's results: a plugin's two builds measured in one invocation).
  std::vector<std::pair<std::string, std::string>> pairs;
  /// A time change counts only when its p-value is below this.
  double alpha = 0.05;
  /// A time change counts only beyond this fraction too (head/base above 1 + band, or below 1 / (1 + band)): the
  /// passes of one run are not independent of the machine's drift between two runs, which the rank test cannot see.
  /// scripts/time-verdicts.sh measures what it must be on a machine (docs/ci-regression.md, "Time verdicts").
  double noise_band = 0.10;
  /// Exit 1 when a cell got slower beyond the noise (verdicts that got worse always do).
  bool fail_on_slower = false;
  /// Exit 0 (not 3) when a cell's verdicts or times cannot be compared; they are still named and not judged.
  bool allow_incomparable = false;
  std::optional<std::filesystem::path> markdown, json;
  /// Where the pairs the head newly misses are written as query files (default: compare-replay).
  std::filesystem::path replay = "compare-replay";
};

/// Compares, prints the table on `out`, writes what the options ask. Returns the exit status: 1 when a verdict got
/// worse (more missed, errors or late TOIs, or answers that changed between passes), or with fail_on_slower a time
/// beyond the noise; else 3 when a cell's verdicts or times could not be compared (unless allow_incomparable); else 0.
/// @throws InputError for a file that is not a result set.
int run_compare(const CompareOptions& options, std::ostream& out);

}  // namespace ccd::harness
