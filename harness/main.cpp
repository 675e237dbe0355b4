// ccdbench: the command line of the harness.

#include "ccd/config.hpp"
#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/input_file.hpp"
#include "datasets/scene_file.hpp"
#include "harness/commands.hpp"
#include "harness/query_scoring.hpp"
#include "harness/registry_listing.hpp"
#include "harness/run.hpp"
#include "harness/run/compare.hpp"
#include "harness/run/provenance.hpp"
#include "harness/work_queue.hpp"
#include "strategies/narrowphase/registry.hpp"
#include "strategies/plugin/isolation.hpp"
#include "strategies/plugin/plugin_narrow_phase.hpp"
#include "strategies/registry.hpp"

#include <CLI/CLI.hpp>

#include <tbb/global_control.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <optional>

namespace {

constexpr const char* kDescription =
    "ccdbench: continuous collision detection of deforming triangle meshes, measured against an exact reference.\n"
    "Every strategy's collision sets are compared with exact truth (rational and algebraic arithmetic), so a\n"
    "reported '0 missed' is a checked statement. Commands print tables for people; --json gives the same for\n"
    "scripts. Bad input (or a bad option) stops with FILE:WHERE: REASON and exit status 2, before anything is\n"
    "written; `check` exits 1 when the gate fails. Under mpirun (mpirun -n N --bind-to none ccdbench ...), run,\n"
    "truth and queries spread their work over the ranks; the output is that of one process (README: Runs on MPI).";

/// At most this many worker threads: far beyond any machine this runs on, and small enough that TBB's per-thread
/// state stays a few megabytes (--threads 1e8 would ask it for gigabytes).
constexpr std::size_t kMaxThreads = 1024;
constexpr int kMaxRepeats = 1000;

/// A refusal of the command line, in the same FILE:WHERE: REASON form as bad input.
int refuse(const std::string& where, const std::string& reason) {
  std::cerr << "ccdbench: error: command line:" << where << (where.empty() ? " " : ": ") << reason << '\n';
  return 2;
}

/// "full, apccd, brute, fcl, fcl-bvh": the registry's strategies.
std::string strategy_names() {
  std::string names;
  for (const ccd::strategies::StrategyEntry& entry : ccd::strategies::strategy_entries()) names += (names.empty() ? "" : ", ") + entry.name;
  return names;
}

/// The methods `queries` takes.
std::string method_names() {
  std::string names;
  for (const std::string& name : ccd::harness::query_method_names()) names += (names.empty() ? "" : ", ") + name;
  return names;
}

std::string version_text() {
  return std::string("ccdbench ") + CCDBENCH_VERSION + " (" + CCDBENCH_BUILD_TYPE + "; OpenCL " + (CCDBENCH_WITH_OPENCL ? "on" : "off") + ", FCL " +
         (CCDBENCH_WITH_FCL ? "on" : "off") + ", MPI " + (CCDBENCH_WITH_MPI ? "on" : "off") +
         (std::string(CCDBENCH_GUARDS_OFF).empty() ? "" : std::string("; plugin-boundary guards OFF: ") + CCDBENCH_GUARDS_OFF + ", a test build") +
         ")";
}

}  // namespace

int run_command_line(int argc, char** argv);

int main(int argc, char** argv) {
  // A plugin's child process (strategies/plugin/isolation.hpp) answers on its pipes and is no rank of anything:
  // handled before MPI is started, so a crash of the plugin never touches the run's ranks.
  if (argc >= 2 && std::string(argv[1]) == ccd::plugin::kPluginHostCommand) return ccd::plugin::serve_plugin(argc, argv);
  // Under mpirun every rank parses the same command line; rank 0 plans and prints, the others work
  // (harness/work_queue.hpp). A failure that one rank alone sees ends every rank, never leaves them waiting.
  const ccd::harness::RankSession ranks(argc, argv);
  const int status = run_command_line(argc, argv);
  if (status != 0) ccd::harness::RankSession::end_all_ranks(status);
  return status;
}

int run_command_line(int argc, char** argv) {
  CLI::App app(kDescription, "ccdbench");
  bool version = false, verbose = false;
  app.add_flag("--version", version, "print ccdbench's version and which optional parts it was built with");
  app.add_flag("--verbose", verbose,
               "with --version: also the build's provenance, as every result records it (revision, build type and flags,\n"
               "compiler, and the version of every library)");
  app.require_subcommand(0, 1);
  std::size_t threads = 0;
  app.add_option(
         "--threads", threads,
         "worker threads for every command, 1 to " + std::to_string(kMaxThreads) + " (default: all cores); verdicts never depend on it, timings do")
      ->check(CLI::Range(std::size_t{1}, kMaxThreads));

  ccd::harness::InspectOptions inspect_options;
  CLI::App* inspect = app.add_subcommand("inspect",
                                         "Print what a file or folder holds: counts of vertices, faces, edges, frames, steps, queries and truth\n"
                                         "positives, and the largest vertex displacement of every step. PATH may be a mesh (.ply/.obj), a frame\n"
                                         "folder or printf pattern (frame_%04d.ply), a scene file (.json, or a folder with scene.json), a\n"
                                         "Scalable-CCD sample step folder, a query file (.csv) or folder, a truth file (mma_bool/*.json), a\n"
                                         "candidate file (boxes/*.json) or a frame cache.");
  inspect->add_option("PATH", inspect_options.paths, "files or folders to describe")->required();
  inspect->add_flag("--json", inspect_options.json, "print one JSON object per PATH (one per line) instead of text");

  ccd::harness::QueriesOptions queries_options;
  std::string methods = "exact";
  CLI::App* queries = app.add_subcommand("queries",
                                         "Score methods on rational query files: per file and in total, queries, truth positives, reported,\n"
                                         "false negatives (FN), false positives (FP) and time per query. Folders are searched for .csv files; a\n"
                                         "file under vertex-face/ or named *vf.csv is vertex-face, under edge-edge/ or *ee.csv edge-edge; truth\n"
                                         "is column 7 or mma_bool/NAME_mma_bool.json beside queries/NAME.csv.");
  queries->add_option("PATH", queries_options.paths, "query files or folders")->required();
  queries
      ->add_option("--method", methods,
                   "comma-separated methods: " + method_names() +
                       " (`exact` is the reference itself;\n"
                       "narrow phases take their keys, NAME:key=value, as `ccdbench strategies` lists them);\n"
                       "plugin:PATH[:key=value] is a plugin's queries (README: Audit your CCD)")
      ->capture_default_str();
  std::vector<std::string> query_answer_files;
  queries->add_option("--answers", query_answer_files,
                      "also score the answers in this CSV (file,index,hit,toi per query, README: Answer files) as a\n"
                      "method: answers:FILE; answers:FILE:method=NAME picks one method of a file that holds several");
  queries->add_option("--write-answers", queries_options.write_answers,
                      "write every method's answer and TOI per query, with the label and the exact TOI floor, as an\n"
                      "answer file (CSV) that --answers reads back");
  // Where plugins run when their spec does not say (isolate=on|off): isolated unless --in-process.
  bool isolate_flag = false, in_process = false;
  auto add_isolation_flags = [&](CLI::App* command) {
    command->add_flag("--isolate", isolate_flag,
                      "run every plugin whose spec does not say isolate=off in a child process (the default): a crash, an\n"
                      "exit or a hang is that query's or step's error, and the run goes on");
    command->add_flag("--in-process", in_process,
                      "run every plugin whose spec does not say isolate=on inside ccdbench (faster for tiny queries; a\n"
                      "crash ends the run, an exit or a hang past timeout= ends it with status 1: README \"Audit your CCD\")");
  };
  add_isolation_flags(queries);
  queries->add_option("--faults", queries_options.faults, "where queries a method gave no answer to are written as query files, to replay")
      ->capture_default_str();
  queries->add_option("--thickness", queries_options.thickness, "thickness δ >= 0 (the data's truth is for 0)")
      ->check(CLI::Range(0.0, std::numeric_limits<double>::max()))
      ->capture_default_str();
  queries->add_option("--repeat", queries_options.repeats, "timing passes per file (1 to 1000); ns/query is their median")
      ->check(CLI::Range(1, kMaxRepeats))
      ->capture_default_str();
  queries->add_flag("--toi", queries_options.toi,
                    "also compare each method's time of impact with the exact earliest contact on the queries that\n"
                    "collide: TOI late (a defect for conservative methods), and the error's mean, median, 99th\n"
                    "percentile (nearest rank) and max, as fractions of the step");
  queries
      ->add_option("--scale-exponent", queries_options.scale_exponent,
                   "multiply every query (and δ) by 2^K first, K in [-1074, 1023]: exact on the rationals; a query\n"
                   "whose doubles are no longer exact is labelled again by the reference, one that overflows left out")
      ->check(CLI::Range(-1074, 1023));
  queries->add_flag("--allow-unlabelled", queries_options.allow_unlabelled,
                    "score files without truth labels too: their FN and FP show as '-' (unlabelled), never as 0, and\n"
                    "the total says how many queries had no label (without this flag such a file is an error)");
  queries->add_option("--json", queries_options.json, "also write the scores as a JSON array to this file");
  queries->add_flag("--sweep", queries_options.sweep,
                    "vary each narrow phase's accuracies, one key at a time, its other keys as given: conservative\n"
                    "tolerance 1e-2..1e-7 then toi_tolerance 1e-2..1e-10, eta 0..1e-2 of the others");
  queries->add_flag("--extremes", queries_options.extremes, "also score the extremes suite (see `ccdbench stress`), labelled by the reference");
  queries->add_option("--report", queries_options.report,
                      "write README.md (the table under the command that made it) and scores.json to this folder");

  ccd::harness::TruthOptions truth_options;
  CLI::App* truth = app.add_subcommand("truth",
                                       "Exact whole-step truth: every vertex-face and edge-edge pair that comes within the thickness during the\n"
                                       "step, found by a certified sort-and-sweep of swept boxes and decided by the reference (certified\n"
                                       "filter, then exact root isolation). Prints the colliding counts and how the pairs were decided.");
  truth->add_option("--frames", truth_options.frames, "two mesh files: the step's first and last frame")->expected(2);
  truth->add_option("--scene", truth_options.scene, "a scene file (or folder with scene.json)");
  truth->add_option("--step", truth_options.step, "step K of the scene: frame K -> K+1")->capture_default_str();
  truth
      ->add_option("--steps", truth_options.steps,
                   "with --scene: N steps from --step on (0: to the last), each stored in the truth cache that `run`\n"
                   "reads; prints a table of every step (under mpirun, the steps are spread over the ranks)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 40))
      ->capture_default_str();
  truth->add_option("--sample", truth_options.sample, "a Scalable-CCD sample step folder: also compare with its own truth");
  truth->add_option("--thickness", truth_options.thickness, "thickness δ >= 0 (default: the scene's; 0 for --frames and --sample)")
      ->check(CLI::Range(0.0, std::numeric_limits<double>::max()));
  truth->add_flag("--toi", truth_options.toi, "also compute every colliding pair's earliest contact time exactly");
  truth->add_option("--json", truth_options.json, "also write the counts and statistics as JSON to this file");

  ccd::harness::StressOptions stress_options;
  std::string stress_methods;
  for (const ccd::narrowphase::NarrowPhaseEntry& entry : ccd::narrowphase::narrow_phases())
    stress_methods += (stress_methods.empty() ? "" : ",") + entry.name;
  CLI::App* stress = app.add_subcommand("stress",
                                        "Run every narrow phase on the extremes suite (coplanar motion, parallel and collinear edges, zero\n"
                                        "motion, touching at t = 0 and 1, exact-thickness distances and one ulp either side, magnitudes from\n"
                                        "1e-12 to 1e9, degenerate primitives, ...), labelled by the exact reference, at δ = 0 and at each case's\n"
                                        "δ > 0. Prints family x variant -> false negatives (FN) and false positives (FP).");
  stress->add_option("--method", stress_methods, "comma-separated narrow-phase specs (`ccdbench strategies` lists them)")->capture_default_str();
  stress->add_option("--seed", stress_options.seed, "seed of the suite's exact transformations")->capture_default_str();
  std::string stress_families;
  stress->add_option("--family", stress_families, "only these families of the suite, comma-separated (default: every family)");
  stress->add_option("--json", stress_options.json, "also write the rows as a JSON array to this file");
  add_isolation_flags(stress);
  stress->add_option("--write-queries", stress_options.write_queries,
                     "also write the suite as rational query files (zero-thickness truth) under this folder");

  ccd::harness::RunOptions run_options;
  std::string run_suite, run_strategies = "full", run_verify = "exact";
  std::vector<std::string> run_frames, run_scenes;
  CLI::App* run = app.add_subcommand("run",
                                     "Run strategies over every step of the scenes, verify every step against the exact truth, and print per\n"
                                     "scene and strategy: ms per step (median; stage breakdown), speed-up over `full` (cells of this run only),\n"
                                     "candidate triangle pairs, elementary tests, colliding pairs, missed (culled: never tested / tested: the\n"
                                     "elementary test said no) and false alarms. Strategies: NAME[+NARROW][:key=value...], comma-separated:\n"
                                     "NAME is " +
                                         strategy_names() + "; NARROW is " + ccd::narrowphase::narrow_phase_list() +
                                         " (default conservative).\n"
                                         "`ccdbench strategies` lists what each is, its keys with their values and defaults, and its backends.\n"
                                         "Truth is cached on disk by content. Finished cells are kept in --out and reused unless --fresh.");
  run->add_option("--suite", run_suite,
                  "built-in suite: ci (seconds), default (what scripts/run.sh runs), paper, large (the spinning\n"
                  "ball at about 1M triangles, 3 steps of contact)");
  run->add_option("--scene", run_scenes, "scene files (or folders with scene.json); repeat or list several");
  run->add_option("--frames", run_frames, "mesh files: one deformable self-colliding object, one step per pair")->expected(2, 100000);
  run->add_option("--strategy", run_strategies, "comma-separated strategy specs")->capture_default_str();
  std::string run_thickness;
  run->add_option("--thickness", run_thickness,
                  "thickness δ >= 0, or `scene` (the scene's own; the default, 0 for --frames); a comma-separated list\n"
                  "(e.g. scene,0) runs every scene at each, and a strategy that refuses one (fcl at δ > 0) is left out there");
  run->add_option("--verify", run_verify, "exact (every step against the exact truth) or none")
      ->check(CLI::IsMember({"exact", "none"}))
      ->capture_default_str();
  run->add_option("--repeat", run_options.repeats, "timed passes (1 to 1000); ms per step is the median")->check(CLI::Range(1, kMaxRepeats));
  run->add_option("--out", run_options.out,
                  "results folder: cells/ (one file per finished cell, reused by a later run only when its inputs,\n"
                  "steps, δ, strategy, repeats, threads and executable are all the same) and results.jsonl (the step\n"
                  "records and summary of every finished cell of every run into this folder)")
      ->capture_default_str();
  run->add_option("--json", run_options.json, "write the summaries (one per scene and strategy) as a JSON array");
  run->add_option("--report", run_options.report, "write a Markdown page (table, steps.json for the plots) here");
  run->add_flag("--toi", run_options.toi,
                "also compare every reported time of impact with the exact earliest contact (exact TOIs are computed\n"
                "once and cached with the truth): toi_late (later than exact: a defect for conservative methods),\n"
                "toi_error_max and toi_error_mean; needs --verify exact");
  run->add_option("--max-steps", run_options.max_steps, "only the first N steps of each scene (0: all)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 40));
  run->add_flag("--fresh", run_options.fresh, "rerun cells kept from an earlier run");
  run->add_option("--misses", run_options.misses,
                  "write each cell's missed pairs here as rational query files by cause (DIR/SCENE/CELL/{vertex-face,"
                  "edge-edge}/CAUSE.csv; cause culled or tested, or for fcl why FCL's test said no), to replay with "
                  "`ccdbench queries`");
  std::vector<std::string> run_answer_folders;
  run->add_option("--answers", run_answer_folders,
                  "also judge the answers in this folder as a strategy, answers:DIR: DIR/SCENE/step_0000.csv, ... one\n"
                  "colliding pair per line (README: Answer files)");
  run->add_option("--write-answers", run_options.write_answers,
                  "write each cell's answers here as DIR/STRATEGY/SCENE/step_0000.csv, ..., as --answers DIR/STRATEGY\n"
                  "reads them (STRATEGY@δ when the run has several δ: a folder of answers is for one δ)");
  add_isolation_flags(run);
  run->add_option("--faults", run_options.faults,
                  "where what a step could not answer (a plugin's errors, crashes, hangs) is written to replay\n"
                  "(default: OUT/faults)");

  std::string baseline_file, write_baseline_file, baseline_margin = "0";
  std::vector<std::string> results_files;
  CLI::App* check =
      app.add_subcommand("check",
                         "The CI gate: exit 1 when it fails, 2 when a file is malformed. It fails when the results are empty, a result\n"
                         "has no baseline entry or an entry no result, a result was not verified or has no colliding pair (it could\n"
                         "not miss anything, so it gates nothing), or a result misses more than its entry allows, has errors\n"
                         "(answers a plugin could not give) beyond its max_errors (default 0), or answers that changed between\n"
                         "passes unless its entry says allow_nondeterministic: true. With --write-baseline it writes the baseline\n"
                         "of the results instead (README: CI regression).");
  CLI::Option* baseline_option =
      check->add_option("--baseline", baseline_file,
                        "JSON array of {scene, strategy, thickness: \"scene\" or a number, max_missed: integer >= 0}, each with optional\n"
                        "steps, colliding, max_toi_late, max_errors (integers) and allow_nondeterministic (true or false)");
  CLI::Option* write_baseline_option =
      check->add_option("--write-baseline", write_baseline_file,
                        "write FILE: one entry per result, the strategy as --strategy gave it, max_missed, max_errors and\n"
                        "max_toi_late (with --toi) as the results have them plus --margin, steps and colliding pinned; results\n"
                        "not verified or without a colliding pair are refused");
  baseline_option->excludes(write_baseline_option);
  check
      ->add_option("--margin", baseline_margin,
                   "with --write-baseline: allow this many more missed pairs, errors and late TOIs than the results show,\n"
                   "a count N or a percentage P% of each (rounded up); default 0")
      ->needs(write_baseline_option);
  std::string check_strategies;
  check->add_option("--strategy", check_strategies,
                    "gate (or write the baseline of) only the results of these strategies, comma-separated, as run's\n"
                    "--strategy gave them: a run of a plugin's base and head builds gates the head alone");
  check->add_option("RESULTS", results_files, "`ccdbench run --json` summary files, taken together")->required();

  ccd::harness::CompareOptions compare_options;
  CLI::App* compare =
      app.add_subcommand("compare",
                         "Compare two result sets of `run`, cell by cell (README: CI regression): missed, errors, false alarms, late TOIs,\n"
                         "the TOI error's median and 99th percentile, memory, and ms per step with the ratio and whether it is beyond the\n"
                         "noise (a two-sided Mann-Whitney U test over the passes' times, exact for small samples; p printed: with --repeat\n"
                         "R on both sides, p can go below 0.05 only from R = 4). With step records (an --out folder, or its results.jsonl)\n"
                         "also the steps whose answers changed and the pairs the head newly misses, written as query files to replay.\n"
                         "Cells are matched by scene, δ and the strategy as given; times are compared only between records of one\n"
                         "machine, build type, compiler and flags. Exit 1 when a verdict got worse (more missed, errors or late TOIs,\n"
                         "answers that now change between passes, a verdict the head lacks, or a cell only the base has), 2 for\n"
                         "a malformed file or a --pair that names no cell, else 0.");
  compare->add_option("BASE", compare_options.base, "the base: a `run --json` file, a run's --out folder or its results.jsonl")->required();
  compare->add_option("HEAD", compare_options.head, "the head, as BASE (may be the same file as BASE with --pair)")->required();
  compare->add_option("--pair", compare_options.pairs,
                      "BASE_SPEC HEAD_SPEC: compare the cells of BASE_SPEC in BASE with those of HEAD_SPEC in HEAD (two builds\n"
                      "of a plugin run in one invocation: BASE and HEAD may then be one file); repeatable");
  compare->add_option("--alpha", compare_options.alpha, "a time change counts when its p-value is below this (default 0.05)")
      ->check(CLI::Range(1e-9, 0.5));
  compare->add_flag("--fail-on-slower", compare_options.fail_on_slower,
                    "also exit 1 when a cell got slower beyond the noise (a cell's passes run one after another, base's\n"
                    "before head's: a machine that slows down between them looks like a slower head; for quiet machines)");
  compare->add_option("--markdown", compare_options.markdown, "also write the comparison as Markdown (a pull request's comment)");
  compare->add_option("--json", compare_options.json, "also write the comparison as JSON, for scripts");
  compare->add_option("--replay", compare_options.replay,
                      "where the newly missed pairs are written as query files, FOLDER/CELL/{vertex-face,edge-edge}/\n"
                      "newly-missed.csv (default: compare-replay)");

  CLI::App* scenes = app.add_subcommand("scenes", "List the built-in procedural scenes, their parameters and defaults.");

  bool strategies_json = false;
  CLI::App* strategies = app.add_subcommand("strategies",
                                            "List the strategies and narrow phases (the registries): what each is, its keys with their values and\n"
                                            "defaults, its backends, and for a strategy what it is judged by and its speed-up baseline.");
  strategies->add_flag("--json", strategies_json, "print one JSON object ({strategies, narrow_phases}) for scripts");
  std::vector<std::string> listed_plugins;
  strategies->add_option("--plugin", listed_plugins, "also list this plugin (a shared library, README: Audit your CCD) with its keys");

  bool devices_json = false;
  CLI::App* devices =
      app.add_subcommand("devices",
                         "List the OpenCL platforms and devices: index (for full:backend=opencl:device=INDEX), name, compute units,\n"
                         "memory, and fp64 (required: the narrow phases are double precision, subnormals kept). Without device=, the\n"
                         "first GPU is used, else device 0. PoCL's CPU device is always there once pocl-opencl-icd is installed.");
  devices->add_flag("--json", devices_json, "one JSON object per device, one per line");

  ccd::harness::GenerateOptions generate_options;
  CLI::App* generate = app.add_subcommand("generate",
                                          "Simulate a built-in scene into a folder: scene.json and one PLY per object per frame\n"
                                          "(OBJECT/frame_0000.ply, ...). The same parameters give bit-identical frames on any thread count, and a\n"
                                          "second call with the same parameters reads the folder's cache instead of simulating again.");
  generate->add_option("NAME", generate_options.name, "scene name (see `ccdbench scenes`)")->required();
  generate->add_option("--resolution", generate_options.resolution, "cloth grid side N (N x N vertices)");
  generate->add_option("--frames", generate_options.frames, "number of frames");
  generate->add_option("--seed", generate_options.seed, "random seed");
  generate->add_option("--first-frame", generate_options.first_frame,
                       "first frame written (the earlier ones are simulated, not written): a scene's late, contact-rich\n"
                       "stretch without its fall, e.g. --frames 30 --first-frame 26 writes 4 frames (3 steps)");
  generate->add_option("--set", generate_options.settings, "any scene parameter, NAME=VALUE (repeatable)");
  generate->add_option("--out", generate_options.out, "output folder")->required();
  generate->add_flag("--report", generate_options.report, "print the scene's measurements for every frame");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& help) {
    return app.exit(help);
  } catch (const CLI::CallForAllHelp& help) {
    return app.exit(help);
  } catch (const CLI::ParseError& error) {
    return refuse({}, error.what() + std::string(" (see ccdbench --help)"));
  }

  if (isolate_flag && in_process) return refuse({}, "--isolate and --in-process say opposite things: give one");
  // Before any plugin's entry is made (its keys' defaults are read then).
  ccd::plugin::set_default_isolation(!in_process);

  if (version) {
    std::cout << version_text() << '\n';
    if (verbose) {
      const nlohmann::json provenance = ccd::harness::build_provenance();
      for (const auto& [name, value] : provenance.items()) {
        std::cout << "  " << name << ": " << (value.is_string() ? value.get<std::string>() : value.dump()) << '\n';
      }
    }
    return 0;
  }
  if (app.get_subcommands().empty()) return refuse({}, "a command is required (see ccdbench --help)");

  std::optional<tbb::global_control> thread_limit;
  if (threads > 0) thread_limit.emplace(tbb::global_control::max_allowed_parallelism, threads);

    // Every output is named by its absolute path before any plugin is loaded (docs/DESIGN.md §10): no working
    // directory a plugin might move to can send results elsewhere.
#if CCDBENCH_GUARD_CHDIR
  for (std::filesystem::path* output : {&run_options.out, &queries_options.faults}) *output = std::filesystem::absolute(*output);
  for (std::optional<std::filesystem::path>* output :
       {&run_options.json, &run_options.report, &run_options.misses, &run_options.faults, &run_options.write_answers, &queries_options.json,
        &queries_options.report, &queries_options.write_answers, &stress_options.json, &stress_options.write_queries}) {
    if (*output) **output = std::filesystem::absolute(**output);
  }
  // And the caches (first used after plugins may have run): a working directory moved by a plugin (a chdir by system
  // call, which no interposer sees) cannot swap them. Scenes are loaded from absolute paths too (below).
  if (const char* cache = std::getenv("CCDBENCH_CACHE_DIR"); cache != nullptr && *cache != '\0') {
    ::setenv("CCDBENCH_CACHE_DIR", std::filesystem::absolute(cache).c_str(), 1);
  }
#endif

  if (ccd::harness::rank_info().size > 1 && !*run && !*truth && !*queries) {
    return ccd::harness::rank_info().rank == 0 ? refuse({}, "only run, truth and queries are spread over MPI ranks: run this command without mpirun")
                                               : 2;
  }

  try {
    if (*inspect) return ccd::harness::run_inspect(inspect_options, std::cout);
    if (*queries) {
      queries_options.methods = CLI::detail::split(methods, ',');
      for (const std::string& file : query_answer_files) queries_options.methods.push_back(std::string("answers:") + file);
      queries_options.command_line = "build/release/bin/ccdbench";
      for (int i = 1; i < argc; ++i) queries_options.command_line += std::string(" ") + argv[i];
      return ccd::harness::run_queries(queries_options, std::cout);
    }
    if (*truth) return ccd::harness::run_truth(truth_options, std::cout);
    if (*scenes) return ccd::harness::run_scenes(std::cout);
    if (*strategies) return ccd::harness::run_strategies(strategies_json, std::cout, listed_plugins);
    if (*devices) return ccd::harness::run_devices(devices_json, std::cout);
    if (*run) {
      const int sources = (run_suite.empty() ? 0 : 1) + (run_scenes.empty() ? 0 : 1) + (run_frames.empty() ? 0 : 1);
      if (sources != 1) return refuse({}, "give exactly one of --suite, --scene, --frames");
      if (!run_suite.empty()) run_options.scenes = ccd::harness::suite_scenes(run_suite);
      // Labels from the paths as given; loads from their absolute paths, fixed now (a scene is loaded when its first
      // cell comes, after plugins may have run).
      for (const std::string& run_scene : run_scenes) {
        const std::filesystem::path absolute = std::filesystem::absolute(run_scene);
        run_options.scenes.push_back({ccd::harness::scene_file_label(run_scene), [absolute] { return ccd::datasets::load_scene_file(absolute); }});
      }
      if (!run_frames.empty()) {
        std::vector<std::filesystem::path> files;
        for (const std::string& frame : run_frames) files.push_back(std::filesystem::absolute(frame));
        const std::filesystem::path first(run_frames[0]);
        const std::string folder = first.parent_path().filename().string();
        run_options.scenes.push_back({(folder.empty() ? "" : folder + "/") + first.filename().string(),
                                      [files] { return ccd::datasets::scene_from_frame_files(files, 0.0); }});
      }
      if (!run_thickness.empty()) {
        for (const std::string& value : CLI::detail::split(run_thickness, ',')) {
          if (value == "scene") {
            run_options.thicknesses.emplace_back(std::nullopt);
            continue;
          }
          std::size_t used = 0;
          double thickness = -1;
          try {
            thickness = std::stod(value, &used);
          } catch (const std::exception&) {
            used = 0;
          }
          if (used == 0 || used != value.size() || !(thickness >= 0) || !std::isfinite(thickness)) {
            return refuse("--thickness " + value, "must be `scene` or a finite number >= 0");
          }
          run_options.thicknesses.emplace_back(thickness);
        }
      }
      run_options.strategies = CLI::detail::split(run_strategies, ',');
      // Answers alone (no --strategy) are judged alone: the default `full` is for runs that name no strategy at all.
      if (!run_answer_folders.empty() && run->count("--strategy") == 0) run_options.strategies.clear();
      for (const std::string& folder : run_answer_folders) run_options.strategies.push_back("answers:" + folder);
      ccd::harness::check_run_outputs(run_options);
      for (const std::string& spec : run_options.strategies) {
        try {
          ccd::strategies::make_strategy(spec);
        } catch (const std::invalid_argument& error) {
          return refuse("--strategy " + spec, error.what());
        }
      }
      run_options.verify = run_verify == "exact";
      if (run_options.toi && !run_options.verify) return refuse("--toi", "TOIs are compared with the exact truth: it needs --verify exact");
      run_options.command_line = "build/release/bin/ccdbench";
      for (int i = 1; i < argc; ++i) run_options.command_line += std::string(" ") + argv[i];
      ccd::harness::run_benchmark(run_options, std::cout);
      return 0;
    }
    if (*check) {
      std::vector<std::pair<std::filesystem::path, nlohmann::json>> results;
      auto read_results = [&] {
        for (const std::string& file : results_files) results.emplace_back(file, ccd::datasets::read_json_file(file, "results file"));
        if (!check_strategies.empty()) results = ccd::harness::select_results(results, CLI::detail::split(check_strategies, ','), std::cout);
      };
      if (!write_baseline_file.empty()) {
        const ccd::harness::BaselineMargin margin = ccd::harness::BaselineMargin::parse(baseline_margin);
        ccd::datasets::require_writable_file(write_baseline_file);
        read_results();
        const nlohmann::json baseline = ccd::harness::write_baseline(results, margin, std::cerr);
        ccd::datasets::write_json_file(write_baseline_file, baseline);
        for (const nlohmann::json& entry : baseline) {
          std::cout << "entry " << entry["scene"].get<std::string>() << " / " << entry["strategy"].get<std::string>() << " / δ "
                    << entry["thickness"].dump() << ": max_missed " << entry["max_missed"] << ", max_errors " << entry.value("max_errors", 0)
                    << (entry.contains("max_toi_late") ? ", max_toi_late " + entry["max_toi_late"].dump() : std::string()) << ", steps "
                    << entry["steps"] << ", colliding " << entry["colliding"] << "\n";
        }
        std::cout << "check: wrote " << baseline.size() << " entr" << (baseline.size() == 1 ? "y" : "ies") << " to " << write_baseline_file << "\n";
        return 0;
      }
      if (baseline_file.empty()) return refuse({}, "check needs --baseline FILE (or --write-baseline FILE to write one)");
      const nlohmann::json baseline = ccd::datasets::read_json_file(baseline_file, "baseline file");
      read_results();
      const bool ok = ccd::harness::check_against_baseline(baseline, baseline_file, results, std::cout);
      std::cout << (ok ? "check: every result within its baseline\n" : "check: FAILED\n");
      return ok ? 0 : 1;
    }
    if (*compare) {
      return ccd::harness::run_compare(compare_options, std::cout);
    }
    if (*stress) {
      stress_options.methods = CLI::detail::split(stress_methods, ',');
      if (!stress_families.empty()) stress_options.families = CLI::detail::split(stress_families, ',');
      return ccd::harness::run_stress_command(stress_options, std::cout);
    }
    if (*generate) return ccd::harness::run_generate(generate_options, std::cout);
  } catch (const ccd::InputError& error) {
    std::cerr << "ccdbench: error: " << error.what() << '\n';
    return 2;
  } catch (const std::invalid_argument& error) {
    // Options that only the command's own code can judge (an unknown method, a generator parameter).
    return refuse({}, error.what());
  } catch (const std::filesystem::filesystem_error& error) {
    // A folder that cannot be listed or a path too long: the path and the system's reason, as bad input.
    std::cerr << "ccdbench: error: " << error.path1().string() << ": " << error.code().message() << '\n';
    return 2;
  } catch (const std::bad_alloc&) {
    std::cerr << "ccdbench: error: out of memory: the input or a parameter asks for more than this machine has\n";
    return 2;
  } catch (const std::exception& error) {
    std::cerr << "ccdbench: error: " << error.what() << '\n';
    return 1;
  }
  return 0;
}
