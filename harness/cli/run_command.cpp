// ccdbench run: strategies over every step of the scenes, verified, timed, recorded (harness/run.hpp).
#include "core/number_text.hpp"
#include "datasets/scene_file.hpp"
#include "harness/cli/cli.hpp"
#include "harness/run.hpp"
#include "harness/run/tables.hpp"
#include "harness/work_queue.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "strategies/registry.hpp"

#include <cmath>
#include <iostream>
#include <memory>

namespace ccd::cli {

namespace {

struct RunCommandOptions {
  harness::RunOptions run;
  std::string suite, strategies = "full", verify = "exact", thickness;
  std::vector<std::string> frames, scenes, answer_folders;
  CLI::App* app = nullptr;
};

/// "full, apccd, brute, fcl, fcl-bvh": the registry's strategies.
std::string strategy_list() {
  std::string names;
  for (const strategies::StrategyEntry& entry : strategies::strategy_entries()) names += (names.empty() ? "" : ", ") + entry.name;
  return names;
}

void add_run_options(CLI::App* run, RunCommandOptions& o, Shared& shared) {
  run->add_option("--suite", o.suite,
                  "built-in suite: ci (seconds), default (what scripts/run.sh runs), paper, large (the spinning\n"
                  "ball at about 1M triangles, 3 steps of contact)");
  run->add_option("--scene", o.scenes, "scene files (or folders with scene.json); repeat or list several");
  run->add_option("--frames", o.frames, "mesh files: one deformable self-colliding object, one step per pair")->expected(2, 100000);
  run->add_option("--strategy", o.strategies, "comma-separated strategy specs")->capture_default_str();
  run->add_option("--thickness", o.thickness,
                  "thickness δ >= 0, or `scene` (the scene's own; the default, 0 for --frames); a comma-separated list\n"
                  "(e.g. scene,0) runs every scene at each, and a strategy that refuses one (fcl at δ > 0) is left out there");
  run->add_option("--verify", o.verify, "exact (every step against the exact truth) or none")
      ->check(CLI::IsMember({"exact", "none"}))
      ->capture_default_str();
  run->add_option("--repeat", o.run.repeats, "timed passes (1 to 1000); ms per step is the median")->check(CLI::Range(1, kMaxRepeats));
  run->add_flag("--interleave", o.run.interleave,
                "run the timed passes of a scene's cells at each δ in turn (pass 1 of every cell, then pass 2, ...):\n"
                "a machine that slows down meanwhile slows every cell alike, and compare then tests two cells' times\n"
                "pass by pass (what a time verdict needs: docs/ci-regression.md, \"Time verdicts\")");
  run->add_option("--out", o.run.out,
                  "results folder: cells/ (one file per finished cell, reused by a later run only when its inputs,\n"
                  "steps, δ, strategy, repeats, threads and executable are all the same, and for a plugin's cell only\n"
                  "with --resume) and results.jsonl (the step records and summary of every finished cell of every run\n"
                  "into this folder)")
      ->capture_default_str();
  run->add_option("--json", o.run.json,
                  "write the summaries (one per scene and strategy) as a JSON array when the run ends (an earlier file\n"
                  "is removed when it starts: a run that stops early leaves none)");
  run->add_option("--report", o.run.report,
                  "write a Markdown page (table, summaries.json and steps.json for the plots) here when the run ends\n"
                  "(those of an earlier run are removed when it starts)");
  run->add_flag("--toi", o.run.toi,
                "also compare every reported time of impact with the exact earliest contact (exact TOIs are computed\n"
                "once and cached with the truth): toi_late (later than exact: a defect for conservative methods),\n"
                "toi_error_max and toi_error_mean; needs --verify exact");
  run->add_option("--max-steps", o.run.max_steps, "only the first N steps of each scene (0: all)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 40));
  run->add_flag("--fresh", o.run.fresh, "rerun cells kept from an earlier run");
  run->add_flag("--resume", o.run.resume,
                "also reuse kept cells of plugins, to finish an interrupted run: without it a plugin's cell is\n"
                "computed again, since its answers can depend on what no digest covers (its environment, files it\n"
                "reads, libraries it opens itself, LD_PRELOAD); a reused one is marked resumed, and check refuses it\n"
                "unless --allow-resumed")
      ->excludes("--fresh");
  run->add_option("--misses", o.run.misses,
                  "write each cell's missed pairs here as rational query files by cause (DIR/SCENE/CELL/{vertex-face,"
                  "edge-edge}/CAUSE.csv; cause culled or tested, or for fcl why FCL's test said no), to replay with "
                  "`ccdbench queries`");
  run->add_option("--answers", o.answer_folders,
                  "also judge the answers in this folder as a strategy, answers:DIR: DIR/SCENE/step_0000.csv, ... one\n"
                  "colliding pair per line (docs/audit.md, Answer files)");
  run->add_option("--write-answers", o.run.write_answers,
                  "write each cell's answers here as DIR/STRATEGY/SCENE/step_0000.csv, ..., as --answers DIR/STRATEGY\n"
                  "reads them (STRATEGY@δ when the run has several δ: a folder of answers is for one δ)");
  add_isolation_flags(run, shared);
  run->add_option("--faults", o.run.faults,
                  "where what a step could not answer (a plugin's errors, crashes, hangs) is written to replay\n"
                  "(default: OUT/faults)");
}

/// The scenes the options name: a suite, scene files, or one object's frames. Labels come from the paths as given,
/// loads from their absolute paths, fixed now (a scene is loaded when its first cell comes, after plugins may have
/// run). Returns a refusal's status, or 0.
int add_run_scenes(RunCommandOptions& o) {
  const int sources = (o.suite.empty() ? 0 : 1) + (o.scenes.empty() ? 0 : 1) + (o.frames.empty() ? 0 : 1);
  if (sources != 1) return refuse({}, "give exactly one of --suite, --scene, --frames");
  if (!o.suite.empty()) o.run.scenes = harness::suite_scenes(o.suite);
  for (const std::string& scene : o.scenes) {
    const std::filesystem::path absolute = std::filesystem::absolute(scene);
    o.run.scenes.push_back({harness::scene_file_label(scene), [absolute] { return datasets::load_scene_file(absolute); }});
  }
  if (!o.frames.empty()) {
    std::vector<std::filesystem::path> files;
    for (const std::string& frame : o.frames) files.push_back(std::filesystem::absolute(frame));
    const std::filesystem::path first(o.frames[0]);
    const std::string folder = first.parent_path().filename().string();
    o.run.scenes.push_back(
        {(folder.empty() ? "" : folder + "/") + first.filename().string(), [files] { return datasets::scene_from_frame_files(files, 0.0); }});
  }
  return 0;
}

/// --thickness: `scene` or numbers, comma-separated. Returns a refusal's status, or 0.
int add_thicknesses(RunCommandOptions& o) {
  if (o.thickness.empty()) return 0;
  for (const std::string& value : CLI::detail::split(o.thickness, ',')) {
    if (value == "scene") {
      o.run.thicknesses.emplace_back(std::nullopt);
      continue;
    }
    const double thickness = parse_double(value).value_or(-1.0);
    if (!(thickness >= 0) || !std::isfinite(thickness)) {
      return refuse("--thickness " + value, "must be `scene` or a finite number >= 0");
    }
    o.run.thicknesses.emplace_back(thickness);
  }
  return 0;
}

int run_run(RunCommandOptions& o, const Shared& shared) {
  harness::RunOptions& run = o.run;
  make_absolute(run.out);
  for (std::optional<std::filesystem::path>* output : {&run.json, &run.report, &run.misses, &run.faults, &run.write_answers}) make_absolute(*output);
  if (const int refused = add_run_scenes(o)) return refused;
  if (const int refused = add_thicknesses(o)) return refused;
  std::vector<std::string> specs = CLI::detail::split(o.strategies, ',');
  // Answers alone (no --strategy) are judged alone: the default `full` is for runs that name no strategy at all.
  if (!o.answer_folders.empty() && o.app->count("--strategy") == 0) specs.clear();
  for (const std::string& folder : o.answer_folders) specs.push_back("answers:" + folder);
  harness::prepare_run_outputs(run);
  run.verify = o.verify == "exact";
  try {
    harness::complete_run_request(run, specs);
  } catch (const harness::RunRequestRefused& refused) {
    return refuse("--" + refused.asked, refused.what());
  }
  if (run.interleave && run.repeats < 6 && harness::rank_info().rank == 0) {
    // The exact signed-rank test's smallest p over R pairs is 2/2^R: below 6 no time change can be called at 0.05.
    std::cerr << "run: warning: --interleave with " << run.repeats << " pass" << (run.repeats == 1 ? "" : "es")
              << ": compare can call no time change from fewer than 6 pairs of passes (use --repeat 9 or more)\n";
  }
  run.command_line = shared.command_line;
  harness::report_run(harness::run_benchmark(run), run, std::cout);
  return 0;
}

}  // namespace

Command add_run(CLI::App& app, Shared& shared) {
  auto options = std::make_shared<RunCommandOptions>();
  options->app = app.add_subcommand("run",
                                    "Run strategies over every step of the scenes, verify every step against the exact truth, and print per\n"
                                    "scene and strategy: ms per step (median; stage breakdown), speed-up over `full` (cells of this run only),\n"
                                    "candidate triangle pairs, elementary tests, colliding pairs, missed (culled: never tested / tested: the\n"
                                    "elementary test said no) and false alarms. Strategies: NAME[+NARROW][:key=value...], comma-separated:\n"
                                    "NAME is " +
                                        strategy_list() + "; NARROW is " + narrowphase::narrow_phase_list() +
                                        " (default conservative).\n"
                                        "`ccdbench strategies` lists what each is, its keys with their values and defaults, and its backends.\n"
                                        "Truth is cached on disk by content. Finished cells are kept in --out and reused unless --fresh (a\n"
                                        "plugin's only with --resume: docs/DESIGN.md §10).");
  add_run_options(options->app, *options, shared);
  return {options->app, [options, &shared] { return run_run(*options, shared); }, true};
}

}  // namespace ccd::cli
