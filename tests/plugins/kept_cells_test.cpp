// The gate judges the code that ran (docs/DESIGN.md §10 "Kept cells"): a plugin's answers can depend on what no
// digest covers, so a cell of it kept from an earlier run never stands for this run's answers unless the user says
// so, and a run that stops before it writes its results leaves no earlier results where check would read them. Each
// test is the round trip a user's CI makes: a run that misses nothing, its baseline, then a change that makes the
// plugin miss without touching its file or the libraries it links, and the same run into the same --out.

#include "tests/plugins/plugin_runs.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <thread>

extern char** environ;

namespace ccd {
namespace {

using testing::cell_of;
using testing::plugin;
using testing::quoted;
using testing::read_json;
using testing::run_ccdbench;
using testing::ScopedVariable;

class KeptCells : public testing::PluginRuns {
 protected:
  /// `ccdbench run` of `spec` on the fold at δ = 0 into the test's --out and --json, with `environment` before the
  /// command ("NAME=VALUE ...").
  testing::CommandResult run(const std::string& spec, const std::string& environment = {}, const std::string& extra = {}) {
    return testing::run_command(environment + " " + CCDBENCH_EXECUTABLE + " run --scene " + quoted(fold()) + " --thickness 0 --strategy " + spec +
                                " --out " + quoted(dir_ / "out") + " --json " + quoted(json()) + " " + extra);
  }
  std::filesystem::path json() const { return dir_ / "results.json"; }
  testing::CommandResult check(const std::string& extra = {}) {
    return run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(json()) + " " + extra);
  }

  /// The first run: it misses nothing, and its baseline is written and passes.
  void accept(const std::string& spec) {
    const auto first = run(spec);
    ASSERT_EQ(first.exit_code, 0) << first.output;
    const nlohmann::json cell = cell_of(read_json(json()), spec);
    ASSERT_GT(cell["colliding"].get<int>(), 0) << "a cell without contact gates nothing";
    ASSERT_EQ(cell["missed"], 0) << first.output;
    accepted_ = cell;
    const auto written = run_ccdbench("check --write-baseline " + quoted(dir_ / "baseline.json") + " " + quoted(json()));
    ASSERT_EQ(written.exit_code, 0) << written.output;
    const auto gate = check();
    ASSERT_EQ(gate.exit_code, 0) << gate.output;
  }

  /// The run again after the plugin's answers changed: its cell is computed again, and the gate fails it.
  void expect_the_gate_fails(const std::string& spec, const std::string& environment = {}) {
    const auto again = run(spec, environment);
    ASSERT_EQ(again.exit_code, 0) << again.output;
    EXPECT_NE(again.output.find("computed again, not kept from an earlier run: a plugin's answers can depend on"), std::string::npos) << again.output;
    const nlohmann::json cell = cell_of(read_json(json()), spec);
    EXPECT_FALSE(cell.value("resumed", false));
    EXPECT_EQ(cell["strategy"], accepted_["strategy"]) << "the plugin's digest changed: its kept cell would not have been found anyway";
    EXPECT_GT(cell["missed"].get<int>() + cell["errors"].get<int>(), 0) << again.output;
    const auto gate = check();
    EXPECT_EQ(gate.exit_code, 1) << gate.output;
  }

  /// The accepted run's cell.
  nlohmann::json accepted_;
};

TEST_F(KeptCells, APluginThatReadsAnEnvironmentVariableIsRunAgain) {
  const std::string spec = "full+plugin:" + plugin("outside_environment").string();
  accept(spec);
  expect_the_gate_fails(spec, "CCDBENCH_TEST_MISS=1");
}

TEST_F(KeptCells, APluginThatReadsAFileIsRunAgain) {
  const std::string spec = "full+plugin:" + copy_of("outside_file").string();
  accept(spec);
  testing::write_text(dir_ / "plugins" / "miss", "miss\n");
  expect_the_gate_fails(spec);
}

TEST_F(KeptCells, APluginThatOpensALibraryItselfIsRunAgain) {
  const std::filesystem::path opener = copy_of("outside_opened");
  replace(opener.parent_path() / "libbroken_dependency.so", plugin("broken_dependency_1"));
  const std::string spec = "full+plugin:" + opener.string();
  accept(spec);
  replace(opener.parent_path() / "libbroken_dependency.so", plugin("broken_dependency_0"));  // rebuilt: it finds nothing now
  expect_the_gate_fails(spec);
}

// LD_PRELOAD of a library (of another name) that defines the one function of the library the wrapper links
// interposes it: the wrapper's file and the library beside it are unchanged, and so is the plugin's digest.
TEST_F(KeptCells, APluginWhoseLinkedSymbolIsInterposedByLdPreloadIsRunAgain) {
  const std::string spec = "full+plugin:" + wrapper(1).string();
  accept(spec);
  expect_the_gate_fails(spec, "ASAN_OPTIONS=verify_asan_link_order=0 LD_PRELOAD=" + quoted(plugin("broken_interposer")));
}

// --resume reuses a plugin's kept cell, to finish an interrupted run: the cell is marked resumed, and check fails it
// (its answers are not this run's) unless --allow-resumed says they may stand for them.
TEST_F(KeptCells, AResumedPluginCellIsGatedOnlyWhenAllowed) {
  const std::string spec = "full+plugin:" + plugin("outside_environment").string();
  accept(spec);
  const auto resumed = run(spec, "CCDBENCH_TEST_MISS=1", "--resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  const nlohmann::json cell = cell_of(read_json(json()), spec);
  EXPECT_TRUE(cell.value("resumed", false)) << resumed.output;
  const auto refused = check();
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
  EXPECT_NE(refused.output.find("its answers were kept from an earlier run (run --resume), not given by the plugin in this run"), std::string::npos)
      << refused.output;
  EXPECT_EQ(check("--allow-resumed").exit_code, 0);
  const auto rewritten = run_ccdbench("check --write-baseline " + quoted(dir_ / "again.json") + " " + quoted(json()));
  EXPECT_EQ(rewritten.exit_code, 2) << "a baseline of what check refuses: " << rewritten.output;
}

// A run that ends before it writes its results (an in-process crash, exit 1; kill -9) leaves no --json: the earlier
// run's file is gone when the run starts, and check on that path fails.
TEST_F(KeptCells, ARunThatCrashesLeavesNoResultsForTheGate) {
  const ScopedVariable quiet("ASAN_OPTIONS", testing::without_segv_reports());
  accept("full");
  const auto crashed = run("full,full+plugin:" + plugin("broken_crash_on_17").string() + ":isolate=off");
  ASSERT_EQ(crashed.exit_code, 1) << crashed.output;
  EXPECT_FALSE(std::filesystem::exists(json())) << "the last good run's results outlived a run that crashed";
  const auto gate = check();
  EXPECT_NE(gate.exit_code, 0) << gate.output;
}

TEST_F(KeptCells, ARunKilledBeforeItEndsLeavesNoResultsForTheGate) {
  accept("full");
  std::vector<std::string> arguments = {CCDBENCH_EXECUTABLE,
                                        "run",
                                        "--scene",
                                        fold().string(),
                                        "--thickness",
                                        "0",
                                        "--strategy",
                                        "full,full+plugin:" + plugin("broken_hang_on_3").string() + ":timeout=60",
                                        "--out",
                                        (dir_ / "out").string(),
                                        "--json",
                                        json().string()};
  std::vector<char*> argv;
  for (std::string& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  pid_t running = -1;
  ASSERT_EQ(::posix_spawn(&running, CCDBENCH_EXECUTABLE, nullptr, nullptr, argv.data(), environ), 0);
  // Killed once it has started (its results file gone), while the plugin hangs; at most 30 s.
  for (int tries = 0; tries < 300 && std::filesystem::exists(json()); ++tries) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ::kill(running, SIGKILL);
  int status = 0;
  ::waitpid(running, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before it was killed";
  const auto gate = check();
  EXPECT_NE(gate.exit_code, 0) << gate.output;
}

}  // namespace
}  // namespace ccd
