// The CI gate as its users run it (docs/ci-regression.md): a baseline written from a run, the gate passing it, and a
// rebuilt plugin that misses one more pair failing it, with compare naming the pair; an interleaved run; and the CI
// example script end to end.

#include "ccd/config.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>
#include <vector>

namespace ccd {
namespace {

using testing::quoted;
using testing::read_json;
using testing::run_ccdbench;

/// The gate's round trip as a user's CI runs it: a plugin built at one path, its baseline written from a run, then a
/// rebuild at that path that misses one more pair.
class GateRoundTrip : public ::testing::Test {
 protected:
  void SetUp() override { ::setenv("CCDBENCH_CACHE_DIR", (dir_ / "cache").c_str(), 1); }
  void TearDown() override {
    ::unsetenv("CCDBENCH_CACHE_DIR");
    ::unsetenv("CCDBENCH_TEST_DROP_SALT");
  }
  /// The candidate plugin is `build` copied to one path (a user's build folder), run on fold 8x8 at δ 0.001.
  testing::CommandResult run(const std::string& build, const std::string& name) {
    std::filesystem::copy_file(std::filesystem::path(CCDBENCH_PLUGIN_DIR) / ("lib" + build + ".so"), dir_ / "libcandidate.so",
                               std::filesystem::copy_options::overwrite_existing);
    return run_ccdbench("run --scene " + quoted(dir_ / "fold8") + " --thickness 0.001 --strategy " + spec() + ",full --verify exact --toi --json " +
                        quoted(dir_ / (name + ".json")) + " --out " + quoted(dir_ / name));
  }
  std::string spec() const { return "plugin:" + (dir_ / "libcandidate.so").string(); }
  nlohmann::json cell(const std::string& name) {
    for (const nlohmann::json& s : read_json(dir_ / (name + ".json"))) {
      if (s["spec"] == spec()) return s;
    }
    return {};
  }
  testing::TempDir dir_;
};

TEST_F(GateRoundTrip, WrittenBaselinePassesAndARebuildMissingOneMorePairFailsIt) {
  testing::small_fold(dir_ / "fold8");
  const auto base = run("my_ccd", "base");
  ASSERT_EQ(base.exit_code, 0) << base.output;
  const std::uint64_t base_missed = cell("base")["missed"];
  ASSERT_GT(cell("base")["colliding"].get<std::uint64_t>(), base_missed + 100);  // pairs found to lose

  const auto written = run_ccdbench("check --write-baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "base.json"));
  ASSERT_EQ(written.exit_code, 0) << written.output;
  const nlohmann::json baseline = read_json(dir_ / "baseline.json");
  ASSERT_EQ(baseline.size(), 2u);
  EXPECT_EQ(baseline[0]["strategy"], spec());  // as given: no digest, no key of the resolved name
  EXPECT_EQ(baseline[0]["max_missed"], base_missed);
  EXPECT_TRUE(baseline[0].contains("max_toi_late") && baseline[0].contains("max_errors") && baseline[0].contains("colliding"));
  const auto passes = run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "base.json"));
  EXPECT_EQ(passes.exit_code, 0) << passes.output;

  // The rebuild drops the queries whose coordinates hash to 0 (one in 1000); a salt that drops exactly one pair
  // the template found is searched for (each salt is deterministic, so this finds the same one every time).
  std::uint64_t head_missed = 0;
  int salt = 0;
  for (; salt < 40; ++salt) {
    ::setenv("CCDBENCH_TEST_DROP_SALT", std::to_string(salt).c_str(), 1);
    const auto head = run("regressed_ccd", "head");
    ASSERT_EQ(head.exit_code, 0) << head.output;
    head_missed = cell("head")["missed"];
    if (head_missed == base_missed + 1) break;
    std::filesystem::remove_all(dir_ / "head");
  }
  ASSERT_EQ(head_missed, base_missed + 1) << "no salt below 40 dropped exactly one found pair";
  std::cout << "salt " << salt << ": " << base_missed << " missed -> " << head_missed << "\n";
  const auto fails = run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "head.json"));
  EXPECT_EQ(fails.exit_code, 1) << fails.output;
  EXPECT_NE(fails.output.find("FAIL fold8 / " + spec()), std::string::npos) << fails.output;
  EXPECT_NE(fails.output.find("missed " + std::to_string(head_missed) + " of"), std::string::npos) << fails.output;
  EXPECT_NE(fails.output.find("baseline allows " + std::to_string(base_missed)), std::string::npos) << fails.output;

  // compare, from the run's --out folders (step records): the cell, the pair, the plugin's new digest.
  const auto compared = run_ccdbench("compare " + quoted(dir_ / "base") + " " + quoted(dir_ / "head") + " --replay " + quoted(dir_ / "replay"));
  EXPECT_EQ(compared.exit_code, 1) << compared.output;
  EXPECT_NE(compared.output.find("fold8 / " + spec() + " / δ 0.001:"), std::string::npos) << compared.output;
  EXPECT_NE(compared.output.find("newly missed at step"), std::string::npos) << compared.output;
  EXPECT_NE(compared.output.find("plugin code changed: digest"), std::string::npos) << compared.output;
  EXPECT_NE(compared.output.find("written to replay: ccdbench queries "), std::string::npos) << compared.output;
  EXPECT_NE(compared.output.find(" --thickness 0.001"), std::string::npos) << compared.output;
  // The written pair is a true contact the rebuild misses when asked alone.
  std::filesystem::path replay;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir_ / "replay")) {
    if (entry.is_regular_file()) replay = entry.path().parent_path().parent_path();
  }
  ASSERT_FALSE(replay.empty());
  const auto replayed = run_ccdbench("queries " + quoted(replay) + " --method plugin:" + (dir_ / "libcandidate.so").string() +
                                     ",exact --thickness 0.001 --json " + quoted(dir_ / "replayed.json"));
  EXPECT_EQ(replayed.exit_code, 0) << replayed.output;
  // Labelled at the cell's δ, which the files say: replayed there, no note that the labels are for another δ.
  EXPECT_EQ(replayed.output.find("labels of"), std::string::npos) << replayed.output;
  bool regressed_missed = false, exact_found = false;
  for (const nlohmann::json& row : read_json(dir_ / "replayed.json")) {
    if (row.value("method", "").rfind("plugin:", 0) == 0) regressed_missed = row.value("false_negatives", 0) == 1;
    if (row.value("method", "") == "exact") exact_found = row.value("false_negatives", 1) == 0;
  }
  EXPECT_TRUE(regressed_missed) << read_json(dir_ / "replayed.json").dump();
  EXPECT_TRUE(exact_found) << read_json(dir_ / "replayed.json").dump();
}

// examples/ci/regression.sh as a user's CI runs it, its builds given (the template, and the rebuild that drops one
// query in 50 as the head): the baseline written, then the gate failing the head and the comparison naming it.
// One step numbering (docs/running.md): from 0, in the messages a run prints ("truth of step K of steps 0-N", a
// pass's progress) as in the step records it writes, which compare and the fault folders name steps by. A fold of 8
// frames has steps 0-6: no message may say "step 7" or "of steps 1-".
TEST_F(GateRoundTrip, StepsAreNumberedFromZeroInMessagesAsInRecords) {
  testing::small_fold(dir_ / "fold8");
  const auto run = run_ccdbench("run --scene " + quoted(dir_ / "fold8") + " --strategy full --out " + quoted(dir_ / "out"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::vector<std::size_t> recorded;
  std::istringstream records(testing::read_text(dir_ / "out" / "results.jsonl"));
  for (std::string line; std::getline(records, line);) {
    const nlohmann::json record = nlohmann::json::parse(line);
    if (record["record"] == "step") recorded.push_back(record["step"].get<std::size_t>());
  }
  ASSERT_EQ(recorded, (std::vector<std::size_t>{0, 1, 2, 3, 4, 5, 6}));
  for (std::size_t k = 0; k < recorded.size(); ++k) {
    EXPECT_NE(run.output.find("truth of step " + std::to_string(k) + " of steps 0-6 computed"), std::string::npos) << k << run.output;
  }
  EXPECT_EQ(run.output.find("step 7"), std::string::npos) << run.output;
  EXPECT_EQ(run.output.find("of steps 1-"), std::string::npos) << run.output;
}

// run --interleave: pass 1 of every cell of a scene at one δ, then pass 2, ...; the cells share one group, each δ its
// own. Without it, a cell's passes run one after another and no group is recorded.
TEST_F(GateRoundTrip, AnInterleavedRunRunsTheCellsPassesInTurn) {
  testing::small_fold(dir_ / "fold8");
  const std::string command =
      "run --scene " + quoted(dir_ / "fold8") + " --thickness scene,0 --strategy full,full+cubic64 --repeat 2 --verify none --fresh";
  const auto interleaved = run_ccdbench(command + " --interleave --out " + quoted(dir_ / "i") + " --json " + quoted(dir_ / "i.json"));
  ASSERT_EQ(interleaved.exit_code, 0) << interleaved.output;
  std::vector<std::string> order;
  std::istringstream lines(interleaved.output);
  for (std::string line; std::getline(lines, line);) {
    if (line.find(" done") != std::string::npos && line.find(": pass ") != std::string::npos) order.push_back(line.substr(line.find("/ ") + 2));
  }
  // Turns in alternating order: no cell always runs first.
  const std::vector<std::string> expected = {"full+conservative: pass 1 of 2 done", "full+cubic64: pass 1 of 2 done",
                                             "full+cubic64: pass 2 of 2 done", "full+conservative: pass 2 of 2 done"};
  ASSERT_EQ(order.size(), 8u) << interleaved.output;
  EXPECT_EQ(std::vector<std::string>(order.begin(), order.begin() + 4), expected) << interleaved.output;
  EXPECT_EQ(std::vector<std::string>(order.begin() + 4, order.end()), expected) << interleaved.output;
  const nlohmann::json cells = read_json(dir_ / "i.json");
  ASSERT_EQ(cells.size(), 4u);
  EXPECT_TRUE(cells[0]["interleave_group"].is_string()) << cells[0].dump();
  EXPECT_EQ(cells[0]["interleave_group"], cells[1]["interleave_group"]);
  EXPECT_EQ(cells[2]["interleave_group"], cells[3]["interleave_group"]);
  EXPECT_NE(cells[0]["interleave_group"], cells[2]["interleave_group"]);
  EXPECT_NE(interleaved.output.find("--interleave with 2 passes: compare can call no time change"), std::string::npos) << interleaved.output;
  // Cells kept from an earlier run did not run in turn with this run's: computed again.
  const std::string again = "run --scene " + quoted(dir_ / "fold8") + " --thickness scene,0 --strategy full,full+cubic64 --repeat 2 --verify none";
  const auto rerun = run_ccdbench(again + " --interleave --out " + quoted(dir_ / "i"));
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  EXPECT_NE(rerun.output.find("computed again, not kept from an earlier run: --interleave"), std::string::npos) << rerun.output;
  const auto apart = run_ccdbench(command + " --out " + quoted(dir_ / "a") + " --json " + quoted(dir_ / "a.json"));
  ASSERT_EQ(apart.exit_code, 0) << apart.output;
  EXPECT_FALSE(read_json(dir_ / "a.json")[0].contains("interleave_group"));
  EXPECT_NE(apart.output.find("full+conservative: pass 2 of 2 done\nrun: fold8 / full+cubic64: pass 1 of 2 done"), std::string::npos) << apart.output;
}

TEST_F(GateRoundTrip, TheCiExampleScriptGatesTheHeadAndComparesItWithTheBase) {
  testing::small_fold(dir_ / "fold8");
  const std::filesystem::path plugins(CCDBENCH_PLUGIN_DIR);
  std::filesystem::create_directories(dir_ / "head-build");
  std::filesystem::copy_file(plugins / "libregressed_ccd.so", dir_ / "head-build" / "libmy_ccd.so");
  const std::string script = quoted(std::filesystem::path(CCDBENCH_SOURCE_DIR) / "examples" / "ci" / "regression.sh");
  const std::string settings = "CCDBENCH=" + quoted(std::filesystem::path(CCDBENCH_EXECUTABLE)) +
                               " PLUGIN=libmy_ccd.so BASELINE=" + quoted(dir_ / "baseline.json") +
                               " RUN_ARGS=" + quoted(std::filesystem::path("--scene " + (dir_ / "fold8").string() + " --thickness 0.001 --toi")) +
                               " CCDBENCH_TEST_DROP_ONE_IN=50 BASE_BUILD=" + quoted(plugins) + " ";
  const std::string arguments = " " + quoted(std::filesystem::path(CCDBENCH_SOURCE_DIR)) + " . . " + quoted(dir_ / "work");
  const auto written = testing::run_command("WRITE_BASELINE=1 HEAD_BUILD=" + quoted(plugins) + " " + settings + script + arguments);
  ASSERT_EQ(written.exit_code, 0) << written.output;
  EXPECT_EQ(read_json(dir_ / "baseline.json")[0]["strategy"], "plugin:head/libmy_ccd.so");
  std::filesystem::remove_all(dir_ / "work");
  // An unchanged plugin, built again in the head's own folder.
  std::filesystem::create_directories(dir_ / "same-build");
  std::filesystem::copy_file(plugins / "libmy_ccd.so", dir_ / "same-build" / "libmy_ccd.so");
  const auto same = testing::run_command("HEAD_BUILD=" + quoted(dir_ / "same-build") + " " + settings + script + arguments);
  EXPECT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(same.output.find("fold8 / plugin:base/libmy_ccd.so → plugin:head/libmy_ccd.so / δ 0.001"), std::string::npos) << same.output;
  EXPECT_NE(same.output.find("no verdict got worse"), std::string::npos) << same.output;
  // Base and head ran in turn (run --interleave): their times are tested pass by pass.
  const nlohmann::json compared = read_json(dir_ / "work" / "compare.json")["cells"];
  ASSERT_EQ(compared.size(), 1u) << compared.dump();
  EXPECT_TRUE(compared[0]["time"]["paired"].get<bool>()) << compared.dump();
  std::filesystem::remove_all(dir_ / "work");
  const auto regressed = testing::run_command("HEAD_BUILD=" + quoted(dir_ / "head-build") + " " + settings + script + arguments);
  EXPECT_EQ(regressed.exit_code, 1) << regressed.output;
  EXPECT_NE(regressed.output.find("FAIL fold8 / plugin:head/libmy_ccd.so / δ 0.001: missed"), std::string::npos) << regressed.output;
  const std::string markdown = testing::read_text(dir_ / "work" / "compare.md");
  EXPECT_NE(markdown.find("**A verdict got worse.**"), std::string::npos) << markdown;
  EXPECT_NE(markdown.find("fold8 / plugin:base/libmy_ccd.so → plugin:head/libmy_ccd.so / δ 0.001"), std::string::npos) << markdown;
  EXPECT_NE(markdown.find("newly missed at step"), std::string::npos) << markdown;
  EXPECT_NE(markdown.find("check: FAILED"), std::string::npos) << markdown;
}

}  // namespace
}  // namespace ccd
