// ccdbench check (the CI gate, or its baseline written) and ccdbench compare (two result sets, cell by cell).
#include "datasets/atomic_file.hpp"
#include "datasets/input_file.hpp"
#include "harness/cli/cli.hpp"
#include "harness/run.hpp"
#include "harness/run/compare.hpp"
#include "harness/run/result_set.hpp"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>

namespace ccd::cli {

namespace {

struct CheckOptions {
  std::string baseline, write_baseline, margin = "0", strategies;
  std::vector<std::string> results;
  harness::GateOptions gate;
};

using Results = std::vector<harness::GateResults>;

Results read_results(const CheckOptions& options) {
  Results results;
  for (const std::string& file : options.results) {
    // A run's --out folder or its results.jsonl, as compare reads them (the latest summary of each cell), or a run's
    // --json array.
    if (std::filesystem::is_directory(file) || std::filesystem::path(file).extension() == ".jsonl") {
      results.push_back({file, harness::read_result_set(file, harness::SummaryUse::gate).summaries});
    } else {
      results.push_back({file, harness::read_summaries(datasets::read_json_file(file, "results file"), file, harness::SummaryUse::gate)});
    }
  }
  if (!options.strategies.empty()) results = harness::select_results(results, CLI::detail::split(options.strategies, ','), std::cout);
  return results;
}

int write_baseline(const CheckOptions& options) {
  const harness::BaselineMargin margin = harness::BaselineMargin::parse(options.margin);
  datasets::require_writable_file(options.write_baseline);
  const nlohmann::json baseline = harness::write_baseline(read_results(options), margin, options.gate, std::cerr);
  datasets::write_json_file(options.write_baseline, baseline);
  for (const nlohmann::json& entry : baseline) {
    std::cout << "entry " << entry["scene"].get<std::string>() << " / " << entry["strategy"].get<std::string>() << " / δ "
              << entry["thickness"].dump() << ": max_missed " << entry["max_missed"] << ", max_errors " << entry.value("max_errors", 0)
              << (entry.contains("max_toi_late") ? ", max_toi_late " + entry["max_toi_late"].dump() : std::string()) << ", steps " << entry["steps"]
              << ", colliding " << entry["colliding"] << "\n";
  }
  std::cout << "check: wrote " << baseline.size() << " entr" << (baseline.size() == 1 ? "y" : "ies") << " to " << options.write_baseline << "\n";
  return 0;
}

int gate(const CheckOptions& options) {
  if (options.baseline.empty()) return refuse({}, "check needs --baseline FILE (or --write-baseline FILE to write one)");
  const nlohmann::json baseline = datasets::read_json_file(options.baseline, "baseline file");
  const harness::GateVerdict verdict = harness::gate_results(baseline, options.baseline, read_results(options), options.gate);
  for (const std::string& line : harness::gate_lines(verdict)) std::cout << line << "\n";
  const bool ok = verdict.passed();
  std::cout << (ok ? "check: every result within its baseline\n" : "check: FAILED\n");
  return ok ? 0 : 1;
}

}  // namespace

Command add_check(CLI::App& app) {
  auto options = std::make_shared<CheckOptions>();
  CLI::App* check =
      app.add_subcommand("check",
                         "The CI gate: exit 1 when it fails, 2 when a file is malformed. It fails when the results are empty, a result\n"
                         "has no baseline entry or an entry no result, a result was not verified or has no colliding pair (it could\n"
                         "not miss anything, so it gates nothing), or a result misses more than its entry allows, has errors\n"
                         "(answers a plugin could not give) beyond its max_errors (default 0), or answers that changed between\n"
                         "passes unless its entry says allow_nondeterministic: true, or is a plugin's cell kept from an earlier\n"
                         "run (run --resume) unless --allow-resumed. With --write-baseline it writes the baseline of the results\n"
                         "instead, refusing what check would fail whatever the entry (docs/ci-regression.md).");
  CLI::Option* baseline_option =
      check->add_option("--baseline", options->baseline,
                        "JSON array of {scene, strategy, thickness: \"scene\" or a number, max_missed: integer >= 0}, each with optional\n"
                        "steps, colliding, max_toi_late, max_errors (integers) and allow_nondeterministic (true or false)");
  CLI::Option* write_baseline_option =
      check->add_option("--write-baseline", options->write_baseline,
                        "write FILE: one entry per result, the strategy as --strategy gave it, max_missed, max_errors and\n"
                        "max_toi_late (with --toi) as the results have them plus --margin, steps and colliding pinned; results\n"
                        "not verified or without a colliding pair are refused");
  baseline_option->excludes(write_baseline_option);
  check
      ->add_option("--margin", options->margin,
                   "with --write-baseline: allow this many more missed pairs, errors and late TOIs than the results show,\n"
                   "a count N or a percentage P% of each (rounded up); default 0")
      ->needs(write_baseline_option);
  check->add_option("--strategy", options->strategies,
                    "gate (or write the baseline of) only the results of these strategies, comma-separated, as run's\n"
                    "--strategy gave them: a run of a plugin's base and head builds gates the head alone");
  check->add_flag("--allow-resumed", options->gate.allow_resumed,
                  "gate a plugin's cells that `run --resume` kept from an earlier run as if the plugin had given their\n"
                  "answers in this run (without it they fail: its answers can depend on what no digest covers)");
  check
      ->add_option("RESULTS", options->results,
                   "results taken together: `ccdbench run --json` files, or a run's --out folders or their results.jsonl\n"
                   "(the latest summary of each cell kept there: every cell of every run into the folder)")
      ->required();
  return {check, [options] { return options->write_baseline.empty() ? gate(*options) : write_baseline(*options); }};
}

Command add_compare(CLI::App& app) {
  auto options = std::make_shared<harness::CompareOptions>();
  CLI::App* compare =
      app.add_subcommand("compare",
                         "Compare two result sets of `run`, cell by cell (docs/ci-regression.md): missed, errors, false alarms, late TOIs,\n"
                         "the TOI error's median and 99th percentile, memory, and ms per step with the ratio and whether it is beyond the\n"
                         "noise. Two cells whose passes ran in turn (one `run --interleave`) are tested pass by pass (Wilcoxon\n"
                         "signed-rank, exact: with R passes p >= 2/2^R) and gated; cells of two runs apart by a Mann-Whitney U test,\n"
                         "shown but never gated (their passes do not sample the machine's drift between the runs). Each p is adjusted for\n"
                         "the number of cells tested alike (Holm), so that identical code run in turn is called slower or faster in\n"
                         "at most alpha of comparisons. With step records (an --out folder, or its results.jsonl)\n"
                         "also the steps whose answers changed and the pairs the head newly misses, written as query files to replay.\n"
                         "Cells are matched by scene, δ and the strategy as given; verdicts are compared only between cells of the same\n"
                         "input (the scene's content, steps, δ), times only between records of one machine, thread count, build,\n"
                         "executable and library versions: a cell that is not is named so on its row and not judged. Exit 1 when a\n"
                         "verdict got worse (more missed, errors or late TOIs, answers that now change between passes, a verdict the\n"
                         "head lacks, or a cell only the base has), 2 for a malformed file or a --pair that names no cell, 3 when a\n"
                         "cell's verdicts or times could not be compared (unless --allow-incomparable), else 0.");
  compare->add_option("BASE", options->base, "the base: a `run --json` file, a run's --out folder or its results.jsonl")->required();
  compare->add_option("HEAD", options->head, "the head, as BASE (may be the same file as BASE with --pair)")->required();
  compare->add_option("--pair", options->pairs,
                      "BASE_SPEC HEAD_SPEC: compare the cells of BASE_SPEC in BASE with those of HEAD_SPEC in HEAD (two builds\n"
                      "of a plugin run in one invocation: BASE and HEAD may then be one file); repeatable");
  compare
      ->add_option("--alpha", options->alpha,
                   "a time change counts when its p-value, adjusted for the cells tested alike (Holm), is below this\n"
                   "(default 0.05): for cells run in turn, the chance that identical code is called slower or faster")
      ->check(CLI::Range(1e-9, 0.5));
  compare
      ->add_option("--noise-band", options->noise_band,
                   "a time change counts only beyond this fraction too, besides p < alpha (default 0.1: head/base above\n"
                   "1.1 or below 1/1.1): a change too small to matter is not called (docs/ci-regression.md, Time verdicts)")
      ->check(CLI::Range(0.0, 10.0));
  compare->add_flag("--fail-on-slower", options->fail_on_slower,
                    "also exit 1 when a cell whose passes ran in turn with the base's (run --interleave) got slower\n"
                    "beyond the noise; times of two runs apart are shown, not gated");
  compare->add_flag("--allow-incomparable", options->allow_incomparable,
                    "exit 0, not 3, when a cell's verdicts (another input) or times (another machine, thread count, build,\n"
                    "executable or library) cannot be compared; they are still named on their rows and not judged");
  compare->add_option("--markdown", options->markdown, "also write the comparison as Markdown (a pull request's comment)");
  compare->add_option("--json", options->json, "also write the comparison as JSON, for scripts");
  compare->add_option("--replay", options->replay,
                      "where the newly missed pairs are written as query files, FOLDER/CELL/{vertex-face,edge-edge}/\n"
                      "newly-missed.csv (default: compare-replay)");
  return {compare, [options] { return harness::run_compare(*options, std::cout); }};
}

}  // namespace ccd::cli
