// Resumed cells (`ccdbench run --out`): a cell is reused only when everything its numbers depend on is the same,
// a corrupt cell file is an error, and results.jsonl keeps every finished cell of every run into the folder.

#include "datasets/atomic_file.hpp"
#include "datasets/procedural_scenes.hpp"
#include "harness/cell_store.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <future>
#include <map>
#include <set>
#include <sstream>
#include <thread>

namespace ccd {
namespace {

using testing::quoted;
using testing::read_json;
using testing::run_ccdbench;

class Resume : public ::testing::Test {
 protected:
  void SetUp() override { ::setenv("CCDBENCH_CACHE_DIR", (dir_ / "cache").c_str(), 1); }
  void TearDown() override { ::unsetenv("CCDBENCH_CACHE_DIR"); }

  /// The kinematic fold with `parameters`, generated into FOLDER (scene.json and PLY frames, so that any ccdbench
  /// executable reads it, with or without that generator).
  std::filesystem::path fold_scene(const std::string& folder, const datasets::SceneParameters& parameters) {
    datasets::generate_procedural_scene({"fold", parameters, dir_ / folder, {}, {}});
    return dir_ / folder;
  }

  /// `ccdbench ARGS --out OUT --json SUMMARY`: the run's summaries (one per cell).
  nlohmann::json run(const std::string& arguments, const std::string& out = "out") {
    const auto summary = dir_ / "summary.json";
    std::filesystem::remove(summary);
    const testing::CommandResult result = run_ccdbench(arguments + " --out " + quoted(dir_ / out) + " --json " + quoted(summary));
    last_output_ = result.output;
    EXPECT_EQ(result.exit_code, 0) << arguments << "\n" << result.output;
    return std::filesystem::exists(summary) ? read_json(summary) : nlohmann::json::array();
  }

  static bool resumed(const nlohmann::json& summaries) {
    for (const auto& s : summaries) {
      if (s.value("resumed", false)) return true;
    }
    return false;
  }

  testing::TempDir dir_;
  std::string last_output_;
};

// Two scene folders with one name ("s") and other motions: the second run must not print the first one's result.
TEST_F(Resume, ACellOfAnotherSceneUnderTheSameLabelIsComputedAgain) {
  const auto first = fold_scene("a/s", {{"resolution", 6}, {"frames", 5}});
  const auto second = fold_scene("b/s", {{"resolution", 6}, {"frames", 5}, {"fold_end", 170}, {"blade_travel", 0.1}});
  const nlohmann::json a = run("run --strategy full --scene " + quoted(first));
  const nlohmann::json b = run("run --strategy full --scene " + quoted(second));
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(a[0]["scene"], b[0]["scene"]) << "the test needs two scenes with one label";
  EXPECT_FALSE(resumed(b)) << last_output_;
  const nlohmann::json alone = run("run --strategy full --scene " + quoted(second), "alone");
  EXPECT_EQ(b[0]["colliding"], alone[0]["colliding"]);
  EXPECT_NE(a[0]["colliding"], b[0]["colliding"]) << "the scenes must differ in their answers for this test to mean anything";
}

// `--frames c0.ply c1.ply` after `--frames c0.ply c1_other.ply`: one label, other frames.
TEST_F(Resume, OtherFramesUnderTheSameLabelAreComputedAgain) {
  fold_scene("g", {{"resolution", 6}, {"frames", 12}});
  std::filesystem::create_directories(dir_ / "f");
  std::filesystem::copy_file(dir_ / "g/sheet/frame_0000.ply", dir_ / "f/c0.ply");
  std::filesystem::copy_file(dir_ / "g/sheet/frame_0001.ply", dir_ / "f/c1.ply");
  std::filesystem::copy_file(dir_ / "g/sheet/frame_0011.ply", dir_ / "f/c1_other.ply");
  const std::string frames = "run --strategy full --thickness 0.05 --frames " + quoted(dir_ / "f/c0.ply") + " ";
  const nlohmann::json near = run(frames + quoted(dir_ / "f/c1.ply"));
  const nlohmann::json far = run(frames + quoted(dir_ / "f/c1_other.ply"));
  EXPECT_EQ(near[0]["scene"], far[0]["scene"]);
  EXPECT_FALSE(resumed(far)) << last_output_;
  EXPECT_NE(near[0]["colliding"], far[0]["colliding"]) << "the steps must differ for this test to mean anything";
  EXPECT_EQ(far[0]["colliding"], run(frames + quoted(dir_ / "f/c1_other.ply"), "alone")[0]["colliding"]);
}

TEST_F(Resume, StepsRepeatsThreadsAndTheExecutableAreInTheKey) {
  const std::string scene = "run --strategy full --scene " + quoted(fold_scene("s", {{"resolution", 6}, {"frames", 6}}));
  const nlohmann::json one_step = run("--threads 1 " + scene + " --max-steps 1");
  ASSERT_EQ(one_step[0]["steps"], 1);
  const nlohmann::json all_steps = run("--threads 1 " + scene);
  EXPECT_FALSE(resumed(all_steps)) << "a --max-steps 1 cell reused by a full run";
  EXPECT_EQ(all_steps[0]["steps"], 5);
  EXPECT_TRUE(resumed(run("--threads 1 " + scene))) << "the same run must be reused: " << last_output_;
  EXPECT_FALSE(resumed(run("--threads 1 " + scene + " --repeat 2"))) << "--repeat must be in the key";
  if (std::thread::hardware_concurrency() >= 2) {  // on one core, --threads 2 runs one thread: the same cell
    EXPECT_FALSE(resumed(run("--threads 2 " + scene))) << "the thread count must be in the key";
  }
  // Another executable (the same program with one byte more: ELF ignores trailing bytes) must not reuse the cells.
  const auto copy = dir_ / "ccdbench-copy";
  std::filesystem::copy_file(CCDBENCH_EXECUTABLE, copy);
  std::ofstream(copy, std::ios::app | std::ios::binary) << '\0';
  std::filesystem::permissions(copy, std::filesystem::perms::owner_exec, std::filesystem::perm_options::add);
  const testing::CommandResult other =
      testing::run_command(quoted(copy) + " --threads 1 run --strategy full --scene " + quoted(dir_ / "s") + " --out " + quoted(dir_ / "out"));
  ASSERT_EQ(other.exit_code, 0) << other.output;
  EXPECT_EQ(other.output.find("(resumed)"), std::string::npos) << "another executable's cell was reused:\n" << other.output;
}

TEST_F(Resume, ACorruptCellFileIsAnErrorNamingItAndFreshRecomputesIt) {
  const std::string scene = "run --strategy full --scene " + quoted(fold_scene("s", {{"resolution", 6}, {"frames", 4}}));
  const nlohmann::json first = run(scene);
  const std::filesystem::path cell = dir_ / "out/cells" / (first[0]["cell"].get<std::string>() + ".json");
  ASSERT_TRUE(std::filesystem::exists(cell));
  std::ifstream in(cell);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  // Another number where a colliding count is: still valid JSON, a different verdict.
  const std::string field = "\"colliding\":";
  const std::size_t at = text.find(field);
  ASSERT_NE(at, std::string::npos);
  const std::size_t digits = text.find_first_not_of("0123456789", at + field.size());
  text.replace(at + field.size(), digits - at - field.size(), "12345");
  testing::write_text(cell, text);
  const auto corrupt = run_ccdbench(scene + " --out " + quoted(dir_ / "out"));
  EXPECT_EQ(corrupt.exit_code, 2) << corrupt.output;
  EXPECT_NE(corrupt.output.find(cell.filename().string() + ":checksum: does not match"), std::string::npos) << corrupt.output;
  EXPECT_EQ(corrupt.output.find("12345"), std::string::npos) << "the corrupt number must never be shown as a result";
  testing::write_text(cell, "{\"key\": ");
  const auto truncated = run_ccdbench(scene + " --out " + quoted(dir_ / "out"));
  EXPECT_EQ(truncated.exit_code, 2) << truncated.output;
  EXPECT_NE(truncated.output.find("malformed JSON"), std::string::npos) << truncated.output;
  const nlohmann::json fresh = run(scene + " --fresh");
  EXPECT_EQ(fresh[0]["colliding"], first[0]["colliding"]);
}

// A kept cell holds its answers' digests, not the answers: --write-answers and --misses used to write nothing for it
// (exit 0). It is computed again, saying why, and the files are written.
TEST_F(Resume, AKeptCellIsComputedAgainForTheFilesARunAsksFor) {
  const std::string scene = "run --strategy full+cubic32 --thickness 0 --scene " + quoted(fold_scene("s", {{"resolution", 6}, {"frames", 6}}));
  const nlohmann::json first = run(scene);
  ASSERT_GT(first[0]["missed"].get<int>(), 0) << "the test needs a cell with misses";
  EXPECT_TRUE(resumed(run(scene)));
  const nlohmann::json answers = run(scene + " --write-answers " + quoted(dir_ / "answers"));
  EXPECT_FALSE(resumed(answers));
  EXPECT_NE(last_output_.find("computed again, not kept from an earlier run: --write-answers needs its answers"), std::string::npos) << last_output_;
  EXPECT_TRUE(std::filesystem::exists(dir_ / "answers/full+cubic32/s/step_0000.csv")) << last_output_;
  const nlohmann::json misses = run(scene + " --misses " + quoted(dir_ / "misses"));
  EXPECT_FALSE(resumed(misses));
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir_ / "misses")) files += entry.is_regular_file() ? 1 : 0;
  EXPECT_GT(files, 0u) << last_output_;
}

TEST_F(Resume, ResultsKeepEveryCellOfEveryRunIntoOneFolder) {
  const std::string scene = "run --scene " + quoted(fold_scene("s", {{"resolution", 6}, {"frames", 4}}));
  run(scene + " --strategy full");
  run(scene + " --strategy apccd");
  std::size_t full = 0, apccd = 0;
  for (const auto& record : testing::read_json_lines(dir_ / "out/results.jsonl")) {
    if (record["record"] != "summary") continue;
    full += record["strategy"].get<std::string>().rfind("full", 0) == 0 ? 1 : 0;
    apccd += record["strategy"].get<std::string>().rfind("apccd", 0) == 0 ? 1 : 0;
  }
  EXPECT_EQ(full, 1u);
  EXPECT_EQ(apccd, 1u);
}

// A run appends each cell's lines to results.jsonl as it finishes: a cell computed again (--fresh) must replace its
// lines, not add a second copy of them.
TEST_F(Resume, ACellComputedAgainReplacesItsLinesInTheResults) {
  const std::string scene = "run --scene " + quoted(fold_scene("s", {{"resolution", 6}, {"frames", 4}}));
  run(scene + " --strategy full,apccd");
  const std::vector<nlohmann::json> first = testing::read_json_lines(dir_ / "out/results.jsonl");
  run(scene + " --strategy apccd,full --fresh");
  const std::vector<nlohmann::json> again = testing::read_json_lines(dir_ / "out/results.jsonl");
  ASSERT_EQ(again.size(), first.size()) << "3 steps and a summary for each of 2 cells";
  std::map<std::string, std::size_t> summaries;
  for (const auto& record : again) summaries[record["strategy"].get<std::string>().substr(0, 5)] += record["record"] == "summary" ? 1 : 0;
  EXPECT_EQ(summaries, (std::map<std::string, std::size_t>{{"apccd", 1}, {"full+", 1}}));
  // Cells in the order they finished: the rerun's apccd before its full.
  EXPECT_EQ(again.back()["strategy"].get<std::string>().substr(0, 5), "full+");
}

// A run killed while appending leaves half a line: the next run into the folder rebuilds the log, even when it computes
// nothing (every cell kept).
TEST_F(Resume, AResultsLogCutShortIsRepairedByTheNextRun) {
  const std::string scene = "run --scene " + quoted(fold_scene("s", {{"resolution", 6}, {"frames", 4}}));
  run(scene + " --strategy full,apccd");
  const std::string whole = testing::read_text(dir_ / "out/results.jsonl");
  std::ofstream(dir_ / "out/results.jsonl", std::ios::binary | std::ios::trunc) << whole.substr(0, whole.size() - 40);
  // Until then a reader says what happened and how it is repaired.
  const testing::CommandResult cut = run_ccdbench("compare " + quoted(dir_ / "out") + " " + quoted(dir_ / "out"));
  EXPECT_EQ(cut.exit_code, 2) << cut.output;
  EXPECT_NE(cut.output.find("cut short"), std::string::npos) << cut.output;
  EXPECT_TRUE(resumed(run(scene + " --strategy full")));
  EXPECT_EQ(testing::read_text(dir_ / "out/results.jsonl"), whole);
}

// A reader of an --out folder waits while a run appends to its results.jsonl (the folder's lock): it never reads half
// of a cell's lines.
TEST_F(Resume, AReaderWaitsForAnAppendToEnd) {
  const std::string scene = "run --scene " + quoted(fold_scene("s", {{"resolution", 6}, {"frames", 4}}));
  run(scene + " --strategy full,apccd");
  const std::string whole = testing::read_text(dir_ / "out/results.jsonl");
  std::future<testing::CommandResult> reader;
  {
    const datasets::FileLock appending(dir_ / "out/.results.lock");
    std::ofstream(dir_ / "out/results.jsonl", std::ios::binary | std::ios::trunc) << whole.substr(0, whole.size() - 40);
    reader = std::async(std::launch::async, [&] { return run_ccdbench("compare " + quoted(dir_ / "out") + " " + quoted(dir_ / "out")); });
    EXPECT_EQ(reader.wait_for(std::chrono::milliseconds(500)), std::future_status::timeout) << "the reader did not wait for the lock";
    std::ofstream(dir_ / "out/results.jsonl", std::ios::binary | std::ios::trunc) << whole;
  }
  const testing::CommandResult read = reader.get();
  EXPECT_EQ(read.exit_code, 0) << read.output;
}

// A run that stops on an error (here a later scene that does not load) after computing a cell again leaves the log
// as the cell files hold it: one copy of each cell.
TEST_F(Resume, ARunStoppedByAnErrorLeavesOneCopyOfEachCell) {
  const std::string scene = quoted(fold_scene("s", {{"resolution", 6}, {"frames", 4}}));
  run("run --scene " + scene + " --strategy full,apccd");
  std::filesystem::create_directories(dir_ / "bad");
  std::ofstream(dir_ / "bad/scene.json") << "{\"objects\": ";
  const testing::CommandResult stopped =
      run_ccdbench("run --scene " + scene + " --scene " + quoted(dir_ / "bad") + " --strategy full,apccd --fresh --out " + quoted(dir_ / "out"));
  ASSERT_EQ(stopped.exit_code, 2) << stopped.output;
  std::size_t summaries = 0;
  for (const auto& record : testing::read_json_lines(dir_ / "out/results.jsonl")) summaries += record["record"] == "summary" ? 1 : 0;
  EXPECT_EQ(summaries, 2u) << "full and apccd, each once";
}

// Under MPI, cells reach rank 0 out of the order they finished. A cell of another scene, δ or strategy is appended
// where it arrives; one that finished before a cell of its own key already in the log is put in its place by a
// rebuild: a reader takes a key's summary by finished_at and its steps by the last lines, which must be one cell's.
TEST_F(Resume, ACellOlderThanOneOfItsKeyGoesInItsPlace) {
  const std::filesystem::path out = dir_ / "log";
  std::filesystem::create_directories(out / "cells");
  const auto cell = [&](const std::string& name, const std::string& strategy, const std::string& finished) {
    const nlohmann::json record = {
        {"key", {{"cell", name}}},
        {"summary", {{"record", "summary"}, {"scene", "s"}, {"thickness", 0.0}, {"strategy", strategy}, {"finished_at", finished}}},
        {"steps", nlohmann::json::array({{{"record", "step"}, {"step", 0}, {"of", name}}})}};
    harness::write_cell(out / "cells" / (name + ".json"), record);
    return std::pair{out / "cells" / (name + ".json"), record};
  };
  const auto finished_in_order = [&] {
    std::vector<std::string> order;
    for (const auto& record : testing::read_json_lines(out / "results.jsonl")) {
      if (record["record"] == "summary") order.push_back(record["finished_at"]);
    }
    return order;
  };
  harness::ResultsLog log(out);
  std::ostringstream warnings;
  const auto [a, a_cell] = cell("a", "full", "2026-01-01T00:00:02.000000Z");
  log.add(a, a_cell, warnings);
  const auto [b, b_cell] = cell("b", "apccd", "2026-01-01T00:00:01.000000Z");
  log.add(b, b_cell, warnings);
  EXPECT_EQ(finished_in_order(), (std::vector<std::string>{"2026-01-01T00:00:02.000000Z", "2026-01-01T00:00:01.000000Z"}))
      << "another key: appended where it arrived";
  const auto [c, c_cell] = cell("c", "full", "2026-01-01T00:00:01.500000Z");
  log.add(c, c_cell, warnings);
  log.finish(warnings);
  EXPECT_EQ(finished_in_order(),
            (std::vector<std::string>{"2026-01-01T00:00:01.000000Z", "2026-01-01T00:00:01.500000Z", "2026-01-01T00:00:02.000000Z"}))
      << "older than full's cell in the log: rebuilt in the order the cells finished";
  EXPECT_EQ(warnings.str(), "");
}

// Two runs into one --out at the same time: neither may drop the other's lines.
TEST_F(Resume, TwoRunsAtOnceIntoOneFolderKeepEachOthersCells) {
  const auto scene = quoted(fold_scene("s", {{"resolution", 8}, {"frames", 12}}));
  const std::string out = " --out " + quoted(dir_ / "out");
  const std::vector<std::string> strategies = {"full", "apccd", "brute", "full+cubic64"};
  std::vector<FILE*> runs;
  for (const std::string& strategy : strategies) {
    runs.push_back(
        ::popen((std::string(CCDBENCH_EXECUTABLE) + " run --scene " + scene + " --strategy " + strategy + out + " > /dev/null 2>&1").c_str(), "r"));
  }
  for (FILE* process : runs) EXPECT_EQ(::pclose(process), 0);
  std::set<std::string> kept;
  for (const auto& record : testing::read_json_lines(dir_ / "out/results.jsonl")) {
    if (record["record"] == "summary") kept.insert(record["strategy"].get<std::string>().substr(0, 5));
  }
  EXPECT_EQ(kept, (std::set<std::string>{"full+", "apccd", "brute"})) << "full and full+cubic64 both begin with 'full+'";
  std::size_t summaries = 0;
  for (const auto& record : testing::read_json_lines(dir_ / "out/results.jsonl")) summaries += record["record"] == "summary" ? 1 : 0;
  EXPECT_EQ(summaries, strategies.size());
}

}  // namespace
}  // namespace ccd
