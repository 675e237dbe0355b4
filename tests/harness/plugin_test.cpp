// Plugins and answer files (strategies/plugin/, docs/audit.md): a user's CCD code, loaded or not, is judged
// like the built-ins; a plugin broken on purpose is reported as the plugin's fault and nothing else is lost.

#include "ccd/config.hpp"
#include "datasets/procedural_scenes.hpp"
#include "datasets/query_file.hpp"
#include "harness/run/records.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

namespace ccd {
namespace {

using testing::cell_of;
using testing::quoted;
using testing::read_json;
using testing::run_ccdbench;

/// A plugin built with the project (examples/, tests/plugins/).
std::string plugin(const std::string& name) { return (std::filesystem::path(CCDBENCH_PLUGIN_DIR) / ("lib" + name + ".so")).string(); }

class Plugins : public ::testing::Test {
 protected:
  void SetUp() override { ::setenv("CCDBENCH_CACHE_DIR", (dir_ / "cache").c_str(), 1); }
  void TearDown() override { ::unsetenv("CCDBENCH_CACHE_DIR"); }

  /// The kinematic fold (106 triangles), generated into FOLDER with its frames: the plugin tests' scene.
  std::filesystem::path fold(std::size_t frames = 8) { return testing::small_fold(dir_ / ("fold" + std::to_string(frames)), frames); }

  /// The first `count` queries of a public edge-edge file, with their labels.
  std::filesystem::path query_file(const std::filesystem::path& data, std::size_t count) {
    datasets::QueryFile file = datasets::read_query_file(data / "sample-queries" / "unit-tests" / "edge-edge" / "data_0_0.csv");
    file.queries.resize(count);
    const std::filesystem::path path = dir_ / "queries" / "edge-edge" / ("first_" + std::to_string(count) + ".csv");
    datasets::write_query_file(path, file.queries);
    return path;
  }

  /// `ccdbench ARGUMENTS --json FILE`: exit status, output and the JSON it wrote.
  std::pair<testing::CommandResult, nlohmann::json> with_json(const std::string& arguments) {
    return testing::run_ccdbench_with_json(arguments, dir_ / "out.json");
  }

  /// The score of `method_head` (its resolved name's start) on file "(all)".
  static nlohmann::json total_of(const nlohmann::json& scores, const std::string& method_head) {
    for (const nlohmann::json& s : scores) {
      if (s["file"] == "(all)" && s["method"].get<std::string>().rfind(method_head, 0) == 0) return s;
    }
    ADD_FAILURE() << "no total for " << method_head << " in " << scores.dump();
    return {};
  }

  testing::TempDir dir_;
};

TEST_F(Plugins, NaiveFloatMissesAndRunSaysWhy) {
  const std::string naive = "plugin:" + plugin("naive_float");
  const std::string out = " --out " + quoted(dir_ / "out") + " --misses " + quoted(dir_ / "misses");
  const auto [run, summaries] = with_json("run --scene " + quoted(fold()) + " --thickness 0 --strategy full,full+" + naive + out);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json full = cell_of(summaries, "full"), plugged = cell_of(summaries, "full+" + naive);
  ASSERT_GT(full["colliding"].get<int>(), 0) << "a scene without contact judges nothing";
  EXPECT_EQ(full["missed"], 0);
  // At δ = 0 a sampling method sees a contact only where it touches at a sample: it misses, each pair tested (the
  // broad phase is ccdbench's) and answered "no".
  EXPECT_GT(plugged["missed"].get<int>(), 0);
  EXPECT_EQ(plugged["missed"], plugged["missed_tested"]);
  EXPECT_EQ(plugged["strategy"].get<std::string>().find(":samples=8:digest="), std::string("full+plugin:").size() + plugin("naive_float").size())
      << "the resolved name holds the plugin's keys and its file's digest";
  // Its misses replay as queries (the first 100 of each kind and cause): the plugin misses every one of them again.
  const std::filesystem::path misses = dir_ / "misses";
  const auto [replay, scores] = with_json("queries " + quoted(misses) + " --method " + naive + ",exact");
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  const nlohmann::json replayed = total_of(scores, "plugin:");
  EXPECT_GT(replayed["queries"].get<int>(), 0);
  EXPECT_EQ(replayed["false_negatives"], replayed["queries"]);
  EXPECT_EQ(total_of(scores, "exact")["false_negatives"], 0);
}

TEST_F(Plugins, BothFormsJudgedAlikeWithTheirCellsResumedAndGated) {
  const std::string p = "plugin:" + plugin("my_ccd");
  const std::string arguments = "run --scene " + quoted(fold()) + " --strategy full," + p + ",full+" + p + " --out " + quoted(dir_ / "out");
  const auto [first, summaries] = with_json(arguments);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const nlohmann::json whole = cell_of(summaries, p), narrow = cell_of(summaries, "full+" + p);
  ASSERT_GT(whole["colliding"].get<int>(), 0);
  // Same method, two broad phases: the template's whole step (a swept-box sweep) finds what ccdbench's BVH does.
  EXPECT_EQ(whole["missed"], narrow["missed"]);
  EXPECT_EQ(whole["reported"], narrow["reported"]);
  EXPECT_EQ(whole["errors"], 0);
  // A plugin's kept cells are computed again unless the run resumes (its answers can depend on what no digest
  // covers); resumed, they are reused, and a rebuilt plugin (another file digest) is another strategy.
  const auto [again, kept] = with_json(arguments + " --resume");
  EXPECT_NE(again.output.find(plugin("my_ccd") + ":digest="), std::string::npos);
  EXPECT_EQ(cell_of(kept, p).value("resumed", false), true) << again.output;
  const std::filesystem::path copy = dir_ / "libcopy.so";
  std::filesystem::copy_file(plugin("my_ccd"), copy);
  const std::string c = "plugin:" + copy.string();
  const std::string copied = "run --scene " + quoted(fold()) + " --strategy " + c + " --out " + quoted(dir_ / "out");
  ASSERT_EQ(with_json(copied).first.exit_code, 0);
  std::ofstream(copy, std::ios::app) << "rebuilt";  // still loads; another digest
  const auto [rebuilt, fresh] = with_json(copied + " --resume");
  ASSERT_EQ(rebuilt.exit_code, 0) << rebuilt.output;
  EXPECT_FALSE(cell_of(fresh, c).value("resumed", false)) << "a cell of another build of the plugin was reused";
  // The gate names a plugin's cell by its spec as given (its resolved name holds an absolute path and a digest).
  const std::filesystem::path results = dir_ / "results.json", baseline = dir_ / "baseline.json";
  std::ofstream(results) << summaries.dump();
  auto gate = [&](int allowed) {
    nlohmann::json entries = nlohmann::json::array();
    for (const nlohmann::json& s : summaries) {
      entries.push_back({{"scene", s["scene"]}, {"strategy", s["spec"]}, {"thickness", "scene"}, {"max_missed", s["spec"] == "full" ? 0 : allowed}});
    }
    std::ofstream(baseline) << entries.dump();
    return run_ccdbench("check --baseline " + quoted(baseline) + " " + quoted(results));
  };
  EXPECT_EQ(gate(whole["missed"].get<int>()).exit_code, 0);
  if (whole["missed"].get<int>() > 0) {
    EXPECT_EQ(gate(whole["missed"].get<int>() - 1).exit_code, 1);
  }
}

// A spec whose digest= names other code is refused before any work, in both forms (the spec is checked without
// loading the plugin: its digest comes from the description).
TEST_F(Plugins, AStaleDigestIsRefusedBeforeAnyWork) {
  for (const std::string prefix : {"", "full+"}) {
    const std::string spec = prefix + "plugin:" + plugin("my_ccd") + ":digest=00000000000000000000000000000000";
    const auto refused = run_ccdbench("run --scene " + quoted(fold()) + " --strategy '" + spec + "' --out " + quoted(dir_ / "stale"));
    EXPECT_EQ(refused.exit_code, 2) << refused.output;
    EXPECT_NE(refused.output.find("--strategy " + spec + ": plugin"), std::string::npos) << refused.output;
    EXPECT_NE(refused.output.find("its code changed"), std::string::npos) << refused.output;
    EXPECT_EQ(refused.output.find("truth of step"), std::string::npos) << refused.output;
  }
}

TEST_F(Plugins, AtZeroThicknessTheTemplateMissesAndTheGateFails) {
  const std::string p = "plugin:" + plugin("my_ccd");
  const auto [run, summaries] = with_json("run --scene " + quoted(fold()) + " --thickness 0 --strategy " + p + " --out " + quoted(dir_ / "out"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json cell = cell_of(summaries, p);
  ASSERT_GT(cell["missed"].get<int>(), 0) << "the template samples distances: at δ = 0 it sees no contact between samples";
  EXPECT_EQ(cell["miss_causes"]["unreported"], cell["missed"]);
  const std::filesystem::path results = dir_ / "results.json", baseline = dir_ / "baseline.json";
  std::ofstream(results) << summaries.dump();
  std::ofstream(baseline) << nlohmann::json::array({{{"scene", cell["scene"]}, {"strategy", p}, {"thickness", 0}, {"max_missed", 0}}}).dump();
  const auto gate = run_ccdbench("check --baseline " + quoted(baseline) + " " + quoted(results));
  EXPECT_EQ(gate.exit_code, 1) << gate.output;
}

TEST_F(Plugins, QueriesAndStressScoreAPlugin) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  const std::string p = "plugin:" + plugin("my_ccd");
  const auto [queries, scores] = with_json("queries " + quoted(data / "sample-queries") + " --method " + p + ",exact");
  ASSERT_EQ(queries.exit_code, 0) << queries.output;
  const nlohmann::json total = total_of(scores, "plugin:");
  EXPECT_EQ(total["queries"], testing::shared_query_count("sample-queries"));
  EXPECT_EQ(total["errors"], 0);
  EXPECT_NE(queries.output.find("errors"), std::string::npos) << "a plugin's table has an errors column";
  const auto stress = run_ccdbench("stress --family zero-motion,parallel-collinear --method " + p + ",conservative");
  ASSERT_EQ(stress.exit_code, 0) << stress.output;
  EXPECT_NE(stress.output.find("plugin:"), std::string::npos) << stress.output;
}

TEST_F(Plugins, ACrashUnderIsolationIsTheQuerysErrorWrittenOut) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  // The children's crashes are this test's input, not findings: under AddressSanitizer each would be reported and
  // symbolized (a quarter of a second each, over a hundred in the run below). With handle_segv=0 a child dies by its
  // signal, as in Release; the sanitizer still watches every other error of both processes.
  const char* before = std::getenv("ASAN_OPTIONS");
  const std::string kept = before == nullptr ? "" : before;
  ::setenv("ASAN_OPTIONS", (kept.empty() ? std::string("handle_segv=0") : kept + ":handle_segv=0").c_str(), 1);
  struct Restore {
    const char* before;
    std::string kept;
    ~Restore() { before == nullptr ? ::unsetenv("ASAN_OPTIONS") : ::setenv("ASAN_OPTIONS", kept.c_str(), 1); }
  } restore{before, kept};
  const std::filesystem::path twenty = query_file(data, 20);
  const std::string crash = "plugin:" + plugin("broken_crash_on_17");
  const auto [run, scores] = with_json("queries " + quoted(twenty) + " --isolate --faults " + quoted(dir_ / "faults") + " --method " + crash);
  ASSERT_EQ(run.exit_code, 0) << "the run finishes: " << run.output;
  const nlohmann::json total = total_of(scores, "plugin:");
  EXPECT_EQ(total["queries"], 20);
  EXPECT_EQ(total["errors"], 1) << "query 17 alone: the child starts again and answers the rest";
  EXPECT_NE(run.output.find("query 17 (line 129)"), std::string::npos) << run.output;
  // Written out: one query, the 17th of the file, to replay.
  std::vector<std::filesystem::path> written;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir_ / "faults")) {
    if (entry.path().extension() == ".csv") written.push_back(entry.path());
  }
  ASSERT_EQ(written.size(), 1u);
  const datasets::QueryFile replay = datasets::read_query_file(written[0]);
  const datasets::QueryFile source = datasets::read_query_file(twenty);
  ASSERT_EQ(replay.queries.size(), 1u);
  EXPECT_EQ(replay.queries[0].rounded, source.queries[16].rounded);
  // In a run: every 17th query of each child crashes it; the cell finishes with those errors (each counted as a miss
  // where the pair collides, errors=miss) and the other cell is whole.
  const auto [steps, summaries] =
      with_json("run --scene " + quoted(fold()) + " --max-steps 3 --isolate --strategy full,full+" + crash + " --out " + quoted(dir_ / "out"));
  ASSERT_EQ(steps.exit_code, 0) << steps.output;
  // --isolate is the default: the spec as given is unchanged (a baseline names it so).
  const nlohmann::json crashed = cell_of(summaries, "full+" + crash);
  EXPECT_GT(crashed["errors"].get<int>(), 0);
  EXPECT_LE(crashed["missed"].get<int>(), crashed["errors"].get<int>()) << "it answers every other query 'contact'";
  EXPECT_EQ(cell_of(summaries, "full")["errors"], 0);
  EXPECT_EQ(cell_of(summaries, "full")["missed"], 0);
  EXPECT_NE(crashed["strategy"].get<std::string>().find(":isolate=on:timeout="), std::string::npos);
  EXPECT_NE(steps.output.find("/FAULTS.txt"), std::string::npos) << steps.output;
  // FAULTS.txt says how to replay its queries, and the command runs as printed: labelled files (at the scene's δ,
  // which they say), no --allow-unlabelled (this plugin crashes on the 17th query of a child: alone, they pass).
  std::string replay_command;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir_ / "out" / "faults")) {
    if (entry.path().filename() != "FAULTS.txt") continue;
    std::ifstream notes(entry.path());
    for (std::string line; std::getline(notes, line) && replay_command.empty();) {
      if (const std::size_t at = line.find("replay: ccdbench queries "); at != std::string::npos) replay_command = line.substr(at + 17);
    }
  }
  ASSERT_FALSE(replay_command.empty()) << "no replay command in FAULTS.txt";
  EXPECT_EQ(replay_command.find("--allow-unlabelled"), std::string::npos) << replay_command;
  const auto replayed = run_ccdbench(replay_command.substr(replay_command.find("queries")));
  EXPECT_EQ(replayed.exit_code, 0) << replay_command << "\n" << replayed.output;
  EXPECT_NE(replayed.output.find("(all)"), std::string::npos) << replayed.output;
  EXPECT_EQ(replayed.output.find("labels of"), std::string::npos) << "replayed at the δ its labels are for: " << replayed.output;
  // Two specs whose names differ only past their first 100 characters write their faults apart (a plugin in a deep
  // folder, so that its resolved name is long wherever the build is).
  const std::filesystem::path deep = dir_ / std::string(100, 'd') / "libcrash.so";
  std::filesystem::create_directories(deep.parent_path());
  std::filesystem::copy_file(plugin("broken_crash_on_17"), deep);
  const std::string both = "plugin:" + deep.string() + ":batch=64,plugin:" + deep.string() + ":batch=128";
  ASSERT_EQ(run_ccdbench("queries " + quoted(twenty) + " --faults " + quoted(dir_ / "apart") + " --method " + both).exit_code, 0);
  std::size_t folders = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir_ / "apart")) folders += entry.is_directory() ? 1 : 0;
  EXPECT_EQ(folders, 2u) << "two methods' faults in one folder";
}

TEST_F(Plugins, AHangIsStoppedByItsTimeout) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  const std::string hang = "plugin:" + plugin("broken_hang_on_3") + ":isolate=on:timeout=0.5";
  const auto [run, scores] = with_json("queries " + quoted(query_file(data, 5)) + " --faults " + quoted(dir_ / "faults") + " --method " + hang);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(total_of(scores, "plugin:")["errors"], 1);
  EXPECT_NE(run.output.find("did not answer within its timeout"), std::string::npos) << run.output;
}

TEST_F(Plugins, NaNTimesOfImpactAreErrorsNeverAnswers) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  const auto [run, scores] = with_json("queries " + quoted(query_file(data, 10)) + " --faults " + quoted(dir_ / "faults") +
                                       " --method plugin:" + plugin("broken_nan_toi") + ",exact");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json total = total_of(scores, "plugin:");
  EXPECT_EQ(total["errors"], 10);
  // An error counts as a miss (errors=miss, the default): every positive is a false negative, none a contact.
  EXPECT_EQ(total["reported"], 0);
  EXPECT_EQ(total["false_negatives"], total["positives"]);
  ASSERT_GT(total["positives"].get<int>(), 0);
  EXPECT_NE(run.output.find("a contact with a TOI that is not a number"), std::string::npos) << run.output;
  // errors=hit counts them as contacts instead, at the start of the step (never late).
  const auto [hit, hit_scores] = with_json("queries " + quoted(query_file(data, 10)) + " --faults " + quoted(dir_ / "faults") +
                                           " --method plugin:" + plugin("broken_nan_toi") + ":errors=hit");
  EXPECT_EQ(total_of(hit_scores, "plugin:")["false_negatives"], 0);
  EXPECT_EQ(total_of(hit_scores, "plugin:")["errors"], 10);
}

// An answer the plugin never writes is its error, not "apart": in-process and in the isolated child alike.
TEST_F(Plugins, AnAnswerLeftUnwrittenIsAnErrorIsolatedOrNot) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  for (const char* isolate : {"", ":isolate=on"}) {
    const auto [run, scores] = with_json("queries " + quoted(query_file(data, 10)) + " --faults " + quoted(dir_ / "faults") +
                                         " --method plugin:" + plugin("broken_silent") + isolate);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const nlohmann::json total = total_of(scores, "plugin:");
    EXPECT_EQ(total["errors"], 10) << isolate;
    EXPECT_EQ(total["reported"], 0) << isolate;
    ASSERT_GT(total["positives"].get<int>(), 0);
    EXPECT_EQ(total["false_negatives"], total["positives"]) << isolate << ": an error counts as a miss (errors=miss)";
  }
}

// In-process (isolated, its child answers one request at a time in any case).
TEST_F(Plugins, APluginThatIsNotThreadSafeRunsOnOneThreadSaidInTheRecord) {
  const std::string single = "plugin:" + plugin("broken_one_thread") + ":isolate=off";
  const auto [run, summaries] =
      with_json("--threads 2 run --scene " + quoted(fold()) + " --strategy full+" + single + " --out " + quoted(dir_ / "out"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json cell = cell_of(summaries, "full+" + single);
  ASSERT_GT(cell["elementary_tests"].get<double>(), 100) << "enough queries that two threads would have shared them";
  EXPECT_EQ(cell["errors"], 0) << "a query came from a second thread";
  EXPECT_NE(cell["provenance"]["threads"].get<std::string>().find("1: narrow phase"), std::string::npos) << cell["provenance"];
}

TEST_F(Plugins, AnotherAbiVersionIsRefusedNamingBoth) {
  const auto run =
      run_ccdbench("run --scene " + quoted(fold()) + " --strategy full+plugin:" + plugin("broken_abi_2") + " --out " + quoted(dir_ / "out"));
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("built for plugin ABI version 2, but this ccdbench speaks version 1"), std::string::npos) << run.output;
}

TEST_F(Plugins, AFaceOutOfRangeIsTheStepsErrorWithItsFramesWrittenOut) {
  const std::string broken = "plugin:" + plugin("broken_face_range");
  const auto [run, summaries] = with_json("run --scene " + quoted(fold()) + " --strategy full," + broken + " --out " + quoted(dir_ / "out"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json cell = cell_of(summaries, broken);
  EXPECT_EQ(cell["errors"], cell["steps"]) << "one refused pair per step";
  EXPECT_EQ(cell["reported"], 0) << "a refused pair is never an answer";
  EXPECT_EQ(cell_of(summaries, "full")["errors"], 0);
  const std::filesystem::path written = cell["errors_written"].get<std::string>();
  std::ifstream notes(written / "FAULTS.txt");
  const std::string text((std::istreambuf_iterator<char>(notes)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("face 106 is out of range (the mesh has 106)"), std::string::npos) << text;
  EXPECT_TRUE(std::filesystem::exists(written / "step_0" / "frame_0.ply"));
  EXPECT_TRUE(std::filesystem::exists(written / "step_0" / "frame_1.ply"));
}

TEST_F(Plugins, QueryAnswerFilesScoreAsTheMethodThatWroteThem) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  const std::filesystem::path answers = dir_ / "answers.csv";
  const std::string queries = "queries " + quoted(data / "sample-queries") + " --toi";
  const auto [written, scores] = with_json(queries + " --method cubic64,advancement --write-answers " + quoted(answers));
  ASSERT_EQ(written.exit_code, 0) << written.output;
  for (const char* method : {"cubic64", "advancement"}) {
    const auto [read, again] = with_json(queries + " --method answers:" + answers.string() + ":method=" + method);
    ASSERT_EQ(read.exit_code, 0) << read.output;
    const nlohmann::json expected = total_of(scores, method), got = total_of(again, "answers:");
    ASSERT_GT(expected["positives"].get<int>(), 0);
    for (const char* field :
         {"queries", "positives", "reported", "false_negatives", "false_positives", "toi_checked", "toi_late", "toi_error_max", "toi_error_mean"}) {
      EXPECT_EQ(got[field], expected[field]) << method << " " << field;
    }
  }
  // A file of two methods needs one named; cut short, mislabelled or not covering the queries, it is refused.
  EXPECT_EQ(run_ccdbench(queries + " --answers " + quoted(answers)).exit_code, 2);
  std::ifstream in(answers);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto refused = [&](const std::string& content, const std::string& reason) {
    const std::filesystem::path bad = dir_ / "bad.csv";
    std::ofstream(bad) << content;
    const auto run = run_ccdbench(queries + " --answers " + quoted(bad) + ":method=cubic64");
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find(bad.string() + ":" + reason), std::string::npos) << run.output;
  };
  refused(text.substr(0, text.size() / 2), "line ");  // cut inside a line
  refused(text.substr(0, text.rfind('\n', text.size() / 2) + 1), " no answer for query ");
  std::string mislabelled = text;
  mislabelled.replace(mislabelled.find("data_0_1.csv"), 12, "data_9_9.csv");
  refused(mislabelled, "line ");
  std::string past_end = text;
  const std::size_t comma = past_end.find(',', past_end.find('\n') + 1);
  past_end.replace(comma + 1, past_end.find(',', comma + 1) - comma - 1, "100000");
  refused(past_end, "line 2: index 100000 is past the end of ");
}

TEST_F(Plugins, StepAnswerFoldersAreJudgedAsTheStrategyThatWroteThem) {
  const std::string scene = " --scene " + quoted(fold()) + " --thickness 0 --out " + quoted(dir_ / "out");
  const auto [written, summaries] = with_json("run" + scene + " --strategy full,full+cubic32 --write-answers " + quoted(dir_ / "answers"));
  ASSERT_EQ(written.exit_code, 0) << written.output;
  for (const char* strategy : {"full", "full+cubic32"}) {
    const std::filesystem::path folder = dir_ / "answers" / strategy;
    const auto [read, again] = with_json("run" + scene + " --answers " + quoted(folder));
    ASSERT_EQ(read.exit_code, 0) << read.output;
    ASSERT_EQ(again.size(), 1u);
    const nlohmann::json expected = cell_of(summaries, strategy);
    ASSERT_GT(expected["colliding"].get<int>(), 0);
    for (const char* field : {"colliding", "missed", "false_alarms", "reported"})
      EXPECT_EQ(again[0][field], expected[field]) << strategy << " " << field;
  }
  // A pair the scene cannot have, a line cut short, a missing step: refused as FILE:line N: REASON.
  const std::filesystem::path folder = dir_ / "answers" / "full";
  const std::string label = "fold8";
  const std::filesystem::path step = folder / label / "step_0000.csv";
  ASSERT_TRUE(std::filesystem::exists(step)) << step;
  std::ifstream original(step);
  std::string first_line;
  ASSERT_TRUE(std::getline(original, first_line) && !first_line.empty()) << "step 0 of the fold collides at δ = 0";
  original.close();
  auto refused = [&](const std::string& content, const std::string& reason) {
    std::ofstream(step) << content;
    const auto run = run_ccdbench("run" + scene + " --answers " + quoted(folder));
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find(step.string() + ":" + reason), std::string::npos) << run.output;
  };
  refused("vf,0,106,0.5\n", "line 1: face 106 is out of range (the mesh has 106)");
  refused(first_line + "\n" + first_line + "\n", std::string("line 2: ") + (first_line.substr(0, 2) == "vf" ? "vertex-face" : "edge-edge"));
  refused("ee,0,1,2\n", "line 1: ee takes 4 indices and an optional TOI, not 3 fields");
  refused("vf,0,5,0.5\nvf,0,5", "line 2: the file ends inside this line");
  std::filesystem::remove(step);
  const auto missing = run_ccdbench("run" + scene + " --answers " + quoted(folder));
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
}

// The walkthrough of docs/audit.md: install ccdbench, build the template against the installed package, and run it through
// every command with the installed program.
TEST_F(Plugins, TheTemplateBuiltAgainstAnInstalledCcdbenchRunsEverywhere) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  const std::filesystem::path prefix = dir_ / "prefix", build = dir_ / "template";
  const std::string cmake = quoted(CCDBENCH_CMAKE);
  const auto install = testing::run_command(cmake + " --install " + quoted(CCDBENCH_BUILD_DIR) + " --prefix " + quoted(prefix));
  ASSERT_EQ(install.exit_code, 0) << install.output;
  for (const char* file : {"bin/ccdbench", "include/ccdbench/ccdbench_plugin.h", "include/ccdbench/ccdbench_plugin.hpp"}) {
    EXPECT_TRUE(std::filesystem::exists(prefix / file)) << file;
  }
  const auto configure = testing::run_command(cmake + " -S " + quoted(std::filesystem::path(CCDBENCH_SOURCE_DIR) / "examples" / "plugin") + " -B " +
                                              quoted(build) + " -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=" + quoted(prefix));
  ASSERT_EQ(configure.exit_code, 0) << configure.output;
  const auto built = testing::run_command(cmake + " --build " + quoted(build));
  ASSERT_EQ(built.exit_code, 0) << built.output;
  const std::string ccdbench = quoted(prefix / "bin" / "ccdbench");
  const std::string p = "plugin:" + (build / "libmy_ccd.so").string();
  auto installed = [&](const std::string& arguments) { return testing::run_command(ccdbench + " " + arguments); };

  const auto queries = installed("queries " + quoted(data / "sample-queries") + " --method " + p + " --json " + quoted(dir_ / "q.json"));
  ASSERT_EQ(queries.exit_code, 0) << queries.output;
  EXPECT_EQ(total_of(read_json(dir_ / "q.json"), "plugin:")["queries"], testing::shared_query_count("sample-queries"));
  const auto stress = installed("stress --family zero-motion --method " + p);
  ASSERT_EQ(stress.exit_code, 0) << stress.output;
  const std::string run_arguments =
      "run --scene " + quoted(fold()) + " --strategy " + p + ",full+" + p + " --out " + quoted(dir_ / "out") + " --json " + quoted(dir_ / "r.json");
  const auto run = installed(run_arguments);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json summaries = read_json(dir_ / "r.json");
  ASSERT_EQ(summaries.size(), 2u);
  ASSERT_GT(summaries[0]["colliding"].get<int>(), 0);
  nlohmann::json baseline = nlohmann::json::array();
  for (const nlohmann::json& s : summaries) {
    baseline.push_back({{"scene", s["scene"]}, {"strategy", s["spec"]}, {"thickness", "scene"}, {"max_missed", s["missed"]}});
  }
  std::ofstream(dir_ / "baseline.json") << baseline.dump();
  const auto gate = installed("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "r.json"));
  EXPECT_EQ(gate.exit_code, 0) << gate.output;
  const auto resumed = installed(run_arguments + " --resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  for (const nlohmann::json& s : read_json(dir_ / "r.json")) EXPECT_TRUE(s.value("resumed", false)) << s["spec"];
}

// A run's records are types with one serializer and one reader (harness/run/records.hpp), which the cell files, the
// MPI exchange, --json and results.jsonl share: every record a run writes reads back into the same JSON, whatever
// it holds (a strategy's counters, errors, misses with their pairs, TOIs, analytic shapes, resumed cells, speed-ups).
TEST_F(Plugins, EveryRecordARunWritesReadsBackAsItWasWritten) {
  const std::string naive = "full+plugin:" + plugin("naive_float"), crash = "full+plugin:" + plugin("broken_crash_on_17");
  const std::filesystem::path shapes = dir_ / "shapes";
  ASSERT_EQ(run_ccdbench("generate fold --resolution 4 --frames 4 --set obstacles=shape --out " + quoted(shapes)).exit_code, 0);
  const std::vector<std::string> runs = {
      "run --scene " + quoted(fold(5)) + " --thickness 0 --toi --repeat 2 --strategy full,apccd," + naive,
      // A cell with errors, kept small: each crash starts a fresh child, about 0.3 s under ASan (this cell took 100 s
      // there over 4 steps and 2 repeats).
      "run --scene " + quoted(fold(5)) + " --thickness 0 --toi --max-steps 1 --strategy " + crash,
      "run --scene " + quoted(shapes) + " --toi --strategy full,apccd",
      // Again: every cell is kept from the first run (resumed).
      "run --scene " + quoted(shapes) + " --toi --strategy full,apccd"};
  std::size_t steps = 0, summaries = 0, with_misses = 0, with_errors = 0, with_shapes = 0, with_counters = 0, resumed = 0;
  nlohmann::json a_step;
  // Every field each record must hold in these runs (each verified, with TOIs): a field the serializer or the
  // reader drops is missing from every file, since each cell passes through both on its way to one.
  const auto holds = [](const nlohmann::json& record, std::vector<std::string> fields) {
    for (const std::string& field : fields) EXPECT_TRUE(record.contains(field)) << field << " missing from " << record.dump().substr(0, 300);
  };
  const std::vector<std::string> environment = {"machine", "build_type", "git_revision", "executable", "provenance", "threads", "rank"};
  const auto reads_back = [&](const nlohmann::json& record) {
    holds(record, environment);
    holds(record,
          {"record", "schema", "scene", "strategy", "thickness", "reported", "colliding", "missed", "missed_culled", "missed_tested", "false_alarms",
           "toi_checked", "toi_late", "toi_error_max", "candidate_pairs", "elementary_tests", "kept_bytes", "history_bytes", "device_bytes"});
    if (record.at("scene") == "shapes") holds(record, {"colliding_face_shape", "missed_face_shape"});
    if (record.value("record", "") == "step") {
      holds(record, {"step", "ms", "ms_repeats", "stages", "answers"});
      if (record.value("errors", 0) > 0) holds(record, {"error_first"});
      if (record.at("missed").get<std::size_t>() > 0) holds(record, {"missed_pairs"});
      a_step = record;
      const harness::StepRecord typed = record.get<harness::StepRecord>();
      EXPECT_EQ(nlohmann::json(typed), record);
      ++steps;
      with_misses += record.contains("missed_pairs");
      with_counters += !typed.counters.empty();
    } else {
      holds(record, {"spec",
                     "triangles",
                     "vertices",
                     "steps",
                     "thickness_from",
                     "ms_per_step",
                     "ms_per_step_mean",
                     "ms_per_repeat",
                     "stage_ms",
                     "stage_ms_mean",
                     "unattributed_ms_mean",
                     "counters",
                     "host_peak_bytes",
                     "host_peak_of",
                     "judged_by",
                     "verified",
                     "repeats",
                     "cell",
                     "errors",
                     "finished_at",
                     "miss_causes",
                     "colliding_by_objects",
                     "faces_in_contact_by_objects",
                     "toi_missing",
                     "toi_error_mean",
                     "toi_error_median",
                     "toi_error_p99",
                     "key"});
      if (record.at("errors").get<std::size_t>() > 0) holds(record, {"errors_written"});
      const harness::CellSummary typed = record.get<harness::CellSummary>();
      EXPECT_EQ(nlohmann::json(typed), record);
      ++summaries;
      with_errors += typed.errors > 0;
      with_shapes += typed.verdict && typed.verdict->colliding_face_shape > 0u;
      resumed += typed.resumed;
    }
  };
  for (const std::string& arguments : runs) {
    const auto [run, written] = with_json(arguments + " --out " + quoted(dir_ / "out"));
    ASSERT_EQ(run.exit_code, 0) << run.output;
    for (const nlohmann::json& summary : written) reads_back(summary);
  }
  for (const auto& entry : std::filesystem::directory_iterator(dir_ / "out" / "cells")) {
    nlohmann::json cell = read_json(entry.path());
    cell.erase("checksum");  // the cell store's, over the record
    const harness::CellRecord typed = cell.get<harness::CellRecord>();
    EXPECT_EQ(nlohmann::json(typed), cell) << entry.path();
    reads_back(cell.at("summary"));
    for (const nlohmann::json& step : cell.at("steps")) reads_back(step);
  }
  for (const nlohmann::json& line : testing::read_json_lines(dir_ / "out" / "results.jsonl")) reads_back(line);
  // What the records held, so that each kind of field was read back at least once.
  EXPECT_GT(steps, 0u);
  EXPECT_GT(summaries, 0u);
  EXPECT_GT(with_misses, 0u) << "naive_float misses at δ = 0";
  EXPECT_GT(with_errors, 0u) << "the 17th query of each child crashes it";
  EXPECT_GT(with_shapes, 0u);
  EXPECT_GT(with_counters, 0u) << "apccd counts its sessions";
  EXPECT_GT(resumed, 0u);
  // A field that is neither the record's nor a counter is refused, not dropped.
  nlohmann::json odd = a_step;
  odd["unknown"] = "text";
  EXPECT_THROW((void)odd.get<harness::StepRecord>(), std::invalid_argument);
}

}  // namespace
}  // namespace ccd
