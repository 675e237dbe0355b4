// ccdbench queries and ccdbench stress: methods scored on query files, and on the extremes suite.
#include "harness/cli/cli.hpp"
#include "harness/commands.hpp"
#include "harness/queries/scoring.hpp"
#include "strategies/narrowphase_registry.hpp"

#include <iostream>
#include <limits>
#include <memory>

namespace ccd::cli {

namespace {

/// The methods `queries` takes.
std::string query_method_list() {
  std::string names;
  for (const std::string& name : harness::query_method_names()) names += (names.empty() ? "" : ", ") + name;
  return names;
}

}  // namespace

Command add_queries(CLI::App& app, Shared& shared) {
  struct Options {
    harness::QueriesOptions queries;
    std::string methods = "exact";
    std::vector<std::string> answer_files;
  };
  auto options = std::make_shared<Options>();
  harness::QueriesOptions& q = options->queries;
  CLI::App* queries = app.add_subcommand("queries",
                                         "Score methods on rational query files: per file and in total, queries, truth positives, reported,\n"
                                         "false negatives (FN), false positives (FP) and time per query. Folders are searched for .csv files; a\n"
                                         "file under vertex-face/ or named *vf.csv is vertex-face, under edge-edge/ or *ee.csv edge-edge; truth\n"
                                         "is column 7 or mma_bool/NAME_mma_bool.json beside queries/NAME.csv.");
  queries->add_option("PATH", q.paths, "query files or folders")->required();
  queries
      ->add_option("--method", options->methods,
                   "comma-separated methods: " + query_method_list() +
                       " (`exact` is the reference itself;\n"
                       "narrow phases take their keys, NAME:key=value, as `ccdbench strategies` lists them);\n"
                       "plugin:PATH[:key=value] is a plugin's queries (docs/audit.md)")
      ->capture_default_str();
  queries->add_option("--answers", options->answer_files,
                      "also score the answers in this CSV (file,index,hit,toi per query, docs/audit.md, Answer files) as a\n"
                      "method: answers:FILE; answers:FILE:method=NAME picks one method of a file that holds several");
  queries->add_option("--write-answers", q.write_answers,
                      "write every method's answer and TOI per query, with the label and the exact TOI floor, as an\n"
                      "answer file (CSV) that --answers reads back");
  add_isolation_flags(queries, shared);
  queries->add_option("--faults", q.faults, "where queries a method gave no answer to are written as query files, to replay")->capture_default_str();
  queries->add_option("--thickness", q.thickness, "thickness δ >= 0 (the data's truth is for 0)")
      ->check(CLI::Range(0.0, std::numeric_limits<double>::max()))
      ->capture_default_str();
  queries->add_option("--repeat", q.repeats, "timing passes per file (1 to 1000); ns/query is their median")
      ->check(CLI::Range(1, kMaxRepeats))
      ->capture_default_str();
  queries->add_flag("--toi", q.toi,
                    "also compare each method's time of impact with the exact earliest contact on the queries that\n"
                    "collide: TOI late (a defect for conservative methods), and the error's mean, median, 99th\n"
                    "percentile (nearest rank) and max, as fractions of the step");
  queries
      ->add_option("--scale-exponent", q.scale_exponent,
                   "multiply every query (and δ) by 2^K first, K in [-1074, 1023]: exact on the rationals; a query\n"
                   "whose doubles are no longer exact is labelled again by the reference, one that overflows left out")
      ->check(CLI::Range(-1074, 1023));
  queries->add_flag("--allow-unlabelled", q.allow_unlabelled,
                    "score files without truth labels too: their FN and FP show as '-' (unlabelled), never as 0, and\n"
                    "the total says how many queries had no label (without this flag such a file is an error)");
  queries->add_option("--json", q.json, "also write the scores as a JSON array to this file");
  queries->add_flag("--sweep", q.sweep,
                    "vary each narrow phase's accuracies, one key at a time, its other keys as given: conservative\n"
                    "tolerance 1e-2..1e-7 then toi_tolerance 1e-2..1e-10, eta 0..1e-2 of the others");
  queries->add_flag("--extremes", q.extremes, "also score the extremes suite (see `ccdbench stress`), labelled by the reference");
  queries->add_option("--report", q.report, "write README.md (the table under the command that made it) and scores.json to this folder");
  return {queries,
          [options, &shared] {
            harness::QueriesOptions& given = options->queries;
            make_absolute(given.faults);
            for (std::optional<std::filesystem::path>* output : {&given.json, &given.report, &given.write_answers}) make_absolute(*output);
            given.methods = CLI::detail::split(options->methods, ',');
            for (const std::string& file : options->answer_files) given.methods.push_back(std::string("answers:") + file);
            given.command_line = shared.command_line;
            return harness::run_queries(given, std::cout);
          },
          true};
}

Command add_stress(CLI::App& app, Shared& shared) {
  struct Options {
    harness::StressOptions stress;
    std::string methods, families;
  };
  auto options = std::make_shared<Options>();
  for (const narrowphase::NarrowPhaseEntry& entry : narrowphase::narrow_phases())
    options->methods += (options->methods.empty() ? "" : ",") + entry.name;
  CLI::App* stress = app.add_subcommand("stress",
                                        "Run every narrow phase on the extremes suite (coplanar motion, parallel and collinear edges, zero\n"
                                        "motion, touching at t = 0 and 1, exact-thickness distances and one ulp either side, magnitudes from\n"
                                        "1e-12 to 1e9, degenerate primitives, ...), labelled by the exact reference, at δ = 0 and at each case's\n"
                                        "δ > 0. Prints family x variant -> false negatives (FN) and false positives (FP).");
  stress->add_option("--method", options->methods, "comma-separated narrow-phase specs (`ccdbench strategies` lists them)")->capture_default_str();
  stress->add_option("--seed", options->stress.seed, "seed of the suite's exact transformations")->capture_default_str();
  stress->add_option("--family", options->families, "only these families of the suite, comma-separated (default: every family)");
  stress->add_option("--json", options->stress.json, "also write the rows as a JSON array to this file");
  add_isolation_flags(stress, shared);
  stress->add_option("--write-queries", options->stress.write_queries,
                     "also write the suite as rational query files (zero-thickness truth) under this folder");
  return {stress, [options] {
            harness::StressOptions& s = options->stress;
            make_absolute(s.json);
            make_absolute(s.write_queries);
            s.methods = CLI::detail::split(options->methods, ',');
            if (!options->families.empty()) s.families = CLI::detail::split(options->families, ',');
            return harness::run_stress_command(s, std::cout);
          }};
}

}  // namespace ccd::cli
