#pragma once
/// @file
/// `ccdbench run`: every strategy over every step of every scene, verified against exact truth, timed, recorded.

#include "datasets/scene_sequence.hpp"
#include "harness/run/options.hpp"
#include "harness/run/records.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace ccd::harness {

/// The scenes of a suite: `ci` (seconds; every scene collides at its δ and at δ = 0, with self contact, contact
/// between objects and contacts inside apccd's sessions), `default` (what scripts/run.sh runs: under two minutes on
/// 2 cores, truth included), `paper` (tens of thousands of triangles, a hundred frames).
/// @throws std::invalid_argument for an unknown suite.
std::vector<SceneSource> suite_scenes(const std::string& suite);

/// The label of a scene given as a file: the folder's name for FOLDER or FOLDER/scene.json, else the file's name.
std::string scene_file_label(const std::filesystem::path& path);

/// A run asked for that cannot be: what was asked ("strategy SPEC", "toi") and why.
struct RunRequestRefused : std::invalid_argument {
  RunRequestRefused(std::string what_asked, const std::string& why) : std::invalid_argument(why), asked(std::move(what_asked)) {}
  std::string asked;
};

/// The one place a run's strategies are parsed and its request checked, for the command line and the C++ API alike:
/// each spec parsed and validated without making anything (every cell carries its spec from here), into
/// options.strategies; TOIs only with verification. @throws RunRequestRefused naming the spec or "toi".
void complete_run_request(RunOptions& options, const std::vector<std::string>& specs);

/// Checks that every output of a run can be written (rank 0's: only it writes them), then removes the results the
/// run writes when it ends (--json, --report's files), so that a run that stops before then leaves none that `check`
/// could take for its own. @throws InputError naming an output that cannot be written (nothing removed then).
void prepare_run_outputs(const RunOptions& options);

/// Runs the cells. Prints nothing but its progress (on stderr); every finished cell is written to --out at once
/// (its cell file, and its lines in results.jsonl: harness/cell_store.hpp's ResultsLog). The table, --json and --report are reporters over the result
/// (report_run, run/tables.hpp). Its strategies are validated specs (strategies::validate).
RunResult run_benchmark(const RunOptions& options);

/// How the gate takes results beyond their entries.
struct GateOptions {
  /// Gate a plugin's cells kept from an earlier run (`run --resume`) as if the plugin had given their answers in
  /// this run (`check --allow-resumed`); without it such a cell fails (docs/DESIGN.md §10 "Kept cells").
  bool allow_resumed = false;
};

/// A results file given to the gate, read (run/result_set.hpp): its summaries, in order.
struct GateResults {
  std::filesystem::path file;
  std::vector<CellSummary> summaries;
};

/// The gate's verdict on one result (or on one baseline entry that no single result matched).
struct GateLine {
  /// The cell ("SCENE / STRATEGY / δ ..."), or the entry; empty for the line on empty results.
  std::string name;
  /// Every reason it fails (a maintainer sees them all at once); none: it passes.
  std::vector<std::string> failures;
  /// What a passing result shows ("missed 0 of 12 <= 0").
  std::string passed;
};

/// The gate's verdict: a line per result, in order, then one per entry with no result or several.
struct GateVerdict {
  std::vector<GateLine> lines;
  bool passed() const;
};

/// The CI gate (`ccdbench check`). The baseline is a JSON array of {scene, strategy, thickness, max_missed}
/// (strategy: the resolved name, or the spec exactly as `run --strategy` was given it, which a plugin's gate uses):
/// thickness is "scene" (the scene's own δ) or the number a cell ran at; max_missed an integer >= 0; optional pins
/// steps and colliding (exactly equal) and max_toi_late (results from a run with --toi). `results` are summaries of
/// `ccdbench run` (several files are taken as one). It passes only when the results are not empty, every result has
/// exactly one baseline entry (and only one) and every entry exactly one result, every result was verified and has at
/// least one colliding pair (a cell that cannot miss proves nothing), and none misses more than its entry allows.
/// @throws InputError (the file, the entry) for a malformed baseline.
GateVerdict gate_results(const nlohmann::json& baseline, const std::filesystem::path& baseline_file, const std::vector<GateResults>& results,
                         const GateOptions& options);

/// The verdict's lines as `check` prints them: a FAIL line per reason a result fails, or its ok line.
std::vector<std::string> gate_lines(const GateVerdict& verdict);

/// Keeps of the results those of the given strategies, each as --strategy gave it (a summary's spec) or its resolved
/// name; says on `out` how many others were left out. @throws InputError when a strategy has no result at all (a
/// misspelt name would otherwise gate nothing).
std::vector<GateResults> select_results(const std::vector<GateResults>& results, const std::vector<std::string>& strategies, std::ostream& out);

/// How much a written baseline allows beyond what the results show, for missed pairs, errors and late TOIs: a count
/// added to each, or a percentage of each (rounded up).
struct BaselineMargin {
  std::uint64_t count = 0;
  double percent = 0;

  /// Parses "N" or "P%" (N an integer >= 0, P a number in [0, 1000]). @throws std::invalid_argument.
  static BaselineMargin parse(const std::string& text);
  std::uint64_t allow(std::uint64_t value) const;
};

/// `ccdbench check --write-baseline`: one entry per result (run --json summaries, several files taken as one), with
/// the strategy as the run was given it, δ as "scene" or the number, max_missed, max_errors and max_toi_late (with
/// --toi) from the result plus the margin, and the steps and colliding pairs pinned. Results that could not be gated are
/// refused, for the reasons check fails them whatever their entry (not verified, no colliding pair, no errors count,
/// a plugin's resumed cell unless allowed), and two results for one cell. A result whose
/// answers changed between passes gets no allow_nondeterministic: it is named on `warnings`, and check fails it until
/// a person says it may. @throws InputError (the file, the entry).
nlohmann::json write_baseline(const std::vector<GateResults>& results, const BaselineMargin& margin, const GateOptions& options,
                              std::ostream& warnings);

}  // namespace ccd::harness
