// Isolation that keeps its word (docs/DESIGN.md §10 "Isolated"): a plugin run in a child process never has another
// request's answer taken for one of its own, leaves no process of its group behind, gets the verdict it would get
// in-process, and its memory is counted in the cell. Each test runs ccdbench as a user would, with a plugin broken on
// purpose (broken_plugin.cpp).

#include "strategies/plugin/child_process.hpp"
#include "strategies/plugin/child_protocol.hpp"
#include "tests/plugins/plugin_runs.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <sstream>
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
using testing::text_of;

class Isolation : public testing::PluginRuns {
 protected:
  /// Families of the extremes suite at unit scale as labelled query files (322 queries, labelled in a few
  /// milliseconds; written by a process that loaded no plugin).
  std::filesystem::path queries() {
    const std::filesystem::path folder = dir_ / "queries";
    if (!std::filesystem::exists(folder)) {
      const auto written = run_ccdbench(
          "stress --family coplanar-motion,parallel-collinear,zero-motion,touch-at-t0-t1,through-edge-or-corner,hourglass,two-roots,near-miss-1e-12,"
          "magnitudes --write-queries " +
          quoted(folder));
      EXPECT_EQ(written.exit_code, 0) << written.output;
    }
    return folder;
  }

  /// Every answer line of `queries --write-answers` (file,index,method,...) by file and index: the method's hit, TOI.
  static std::map<std::string, std::string> answers_of(const std::filesystem::path& file) {
    std::map<std::string, std::string> answers;
    std::istringstream lines(text_of(file));
    std::string line;
    std::getline(lines, line);  // the header
    for (; std::getline(lines, line);) {
      std::vector<std::string> fields;
      std::istringstream split(line);
      for (std::string field; std::getline(split, field, ',');) fields.push_back(field);
      if (fields.size() < 5 || fields[2].rfind("plugin:", 0) != 0) continue;
      answers[fields[0] + "#" + fields[1]] = fields[3] + "," + fields[4];
    }
    return answers;
  }

  /// Whether the process `pid` is gone (or dead, not yet reaped), within five seconds.
  static bool gone(pid_t pid) {
    for (int tries = 0; tries < 100; ++tries) {
      const std::string stat = text_of("/proc/" + std::to_string(pid) + "/stat");
      if (stat.empty() || stat.find(") Z") != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }

  /// The pids the plugin fork_at_load wrote (the processes it forked at load), killed once the test has looked.
  std::vector<pid_t> forked() {
    std::vector<pid_t> pids;
    std::istringstream lines(text_of(dir_ / "pids"));
    for (pid_t pid = 0; lines >> pid;) pids.push_back(pid);
    return pids;
  }
  void expect_every_forked_process_gone(const char* after) {
    const std::vector<pid_t> pids = forked();
    EXPECT_FALSE(pids.empty()) << after << ": the plugin forked nothing, so this proves nothing";
    for (pid_t pid : pids) {
      EXPECT_TRUE(gone(pid)) << after << ": process " << pid << " the plugin forked at load is still running";
      ::kill(pid, SIGKILL);
    }
    std::filesystem::remove(dir_ / "pids");
  }
};

// A plugin whose fork returns from the call: two processes answered on one pipe. The second "done" of a batch used
// to finish the next batch at once with the previous batch's answers still in the shared memory (44 false negatives
// for a plugin with none, 0 errors). Numbering every reply and answer then made a late reply the batch's error, but a
// copy that replied only after the run's last read went unseen (once, in CI). Now the copy ends as it returns from
// the call, before it answers or reads a request: every answer is the plugin's own, and none is an error, whatever
// the timing.
TEST_F(Isolation, APluginWhoseForkReturnsGivesNoOtherQuerysAnswer) {
  // Batches of 64: the queries of a file go in several, so that a copy left answering would meet the next.
  const std::string p = "plugin:" + plugin("broken_fork_returns").string() + ":batch=64";
  const std::string score = "queries " + quoted(queries()) + " --method " + p + " --faults " + quoted(dir_ / "faults") + " --write-answers ";
  const auto clean = run_ccdbench(score + quoted(dir_ / "clean.csv"));
  ASSERT_EQ(clean.exit_code, 0) << clean.output;
  const std::filesystem::path copies = dir_ / "copies";
  // What the copies did: each says it was forked, and each call it made after.
  auto expect_copies_never_called = [&](const std::string& output) {
    const std::string said = text_of(copies);
    EXPECT_NE(said.find(" forked\n"), std::string::npos) << "the plugin never forked: this proves nothing\n" << output;
    EXPECT_EQ(said.find(" called\n"), std::string::npos) << "a copy the plugin forked answered beside the child:\n" << said;
    std::filesystem::remove(copies);
  };
  const ScopedVariable forking("CCDBENCH_TEST_FORK_ON", "5");
  const ScopedVariable told("CCDBENCH_TEST_PID_FILE", copies.string());
  const auto forked = run_ccdbench(score + quoted(dir_ / "forked.csv") + " --json " + quoted(dir_ / "forked.json"));
  ASSERT_EQ(forked.exit_code, 0) << forked.output;
  EXPECT_EQ(answers_of(dir_ / "forked.csv"), answers_of(dir_ / "clean.csv")) << "another query's answer, or an error";
  EXPECT_EQ(read_json(dir_ / "forked.json").back().value("changed_between_passes", std::size_t{0}), 0u);
  expect_copies_never_called(forked.output);

  // In a run: the clean run's verdicts, with no error and no nondeterminism.
  const std::string run = "run --scene " + quoted(fold()) + " --thickness 0 --strategy full+" + p + " --out " + quoted(dir_ / "out");
  const ScopedVariable once("CCDBENCH_TEST_FORK_ON", "");
  const auto [clean_run, clean_cells] = with_json(run);
  ASSERT_EQ(clean_run.exit_code, 0) << clean_run.output;
  const nlohmann::json before = cell_of(clean_cells, "full+" + p);
  ASSERT_GT(before["colliding"].get<int>(), 0);
  std::filesystem::remove(copies);
  const ScopedVariable again("CCDBENCH_TEST_FORK_ON", "5");
  const auto [forked_run, forked_cells] = with_json(run);
  ASSERT_EQ(forked_run.exit_code, 0) << forked_run.output;
  const nlohmann::json after = cell_of(forked_cells, "full+" + p);
  EXPECT_EQ(after["errors"], 0) << forked_run.output;
  EXPECT_FALSE(after.contains("nondeterministic_at_step")) << forked_run.output;
  for (const char* field : {"colliding", "missed", "false_alarms"}) EXPECT_EQ(after[field], before[field]) << field;
  expect_copies_never_called(forked_run.output);
}

// `queries` audits a plugin that misses as `run` does: asked once (--repeat 1), it answers the file again, untimed, and
// the answers that changed are counted. errors_later answers "apart" to its first 200 queries and "error" after:
// on the second file its answers change between the pass and the audit (it had no audit: 0 changed).
TEST_F(Isolation, QueriesAuditsAPluginThatMissesAsRunDoes) {
  const auto scored = run_ccdbench("queries " + quoted(queries()) + " --method plugin:" + plugin("broken_errors_later").string() + " --faults " +
                                   quoted(dir_ / "faults") + " --json " + quoted(dir_ / "q.json"));
  ASSERT_EQ(scored.exit_code, 0) << scored.output;
  const nlohmann::json rows = read_json(dir_ / "q.json");
  const nlohmann::json& total = rows.back();
  ASSERT_EQ(total["file"], "(all)");
  ASSERT_GT(total["false_negatives"].get<int>(), 0) << "a method that misses nothing is not audited";
  EXPECT_GT(total["changed_between_passes"].get<int>(), 0) << scored.output;
}

// What a plugin forks at load is in its child's process group: gone after the description, after a run, and after
// ccdbench itself is killed (the child ends its group then, not only itself).
TEST_F(Isolation, NoProcessOfThePluginsGroupOutlivesItsChild) {
  const ScopedVariable pid_file("CCDBENCH_TEST_PID_FILE", (dir_ / "pids").string());
  const std::string p = "plugin:" + plugin("broken_fork_at_load").string();
  const auto described = run_ccdbench("strategies --plugin " + plugin("broken_fork_at_load").string());
  ASSERT_EQ(described.exit_code, 0) << described.output;
  expect_every_forked_process_gone("after plugin-host --describe");
  const auto ran = run_ccdbench("run --scene " + quoted(fold()) + " --max-steps 2 --strategy full+" + p + " --out " + quoted(dir_ / "out"));
  ASSERT_EQ(ran.exit_code, 0) << ran.output;
  expect_every_forked_process_gone("after a run");

  std::vector<std::string> arguments = {CCDBENCH_EXECUTABLE, "run",       "--scene", fold().string(),           "--repeat", "1000",
                                        "--strategy",        "full+" + p, "--out",   (dir_ / "killed").string()};
  std::vector<char*> argv;
  for (std::string& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  pid_t running = -1;
  ASSERT_EQ(::posix_spawn(&running, CCDBENCH_EXECUTABLE, nullptr, nullptr, argv.data(), environ), 0);
  // Killed once its cell's child has forked (the description's fork, then the child's), at most 30 s.
  for (int tries = 0; tries < 300 && forked().size() < 2; ++tries) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ::kill(running, SIGKILL);
  int status = 0;
  ::waitpid(running, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before it was killed";
  expect_every_forked_process_gone("after kill -9 of ccdbench");
}

// A child whose requests end returns on its own, and used to leave the group's end to its parent (end_child kills it
// once the child has ended): a parent killed between the two (kill -9 of ccdbench just as it ended a child, 1 run in
// about 15 of the test above under load) left what the plugin started running with parent 1. The child now ends the
// rest of its group itself before it exits. Here the test is the parent, and never ends the group.
TEST_F(Isolation, AChildThatEndsTakesWhatThePluginStartedWithIt) {
  const ScopedVariable pid_file("CCDBENCH_TEST_PID_FILE", (dir_ / "pids").string());
  int requests[2], replies[2], lifeline[2];
  ASSERT_EQ(::pipe2(requests, O_CLOEXEC), 0);
  ASSERT_EQ(::pipe2(replies, O_CLOEXEC), 0);
  ASSERT_EQ(::pipe2(lifeline, O_CLOEXEC), 0);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, requests[0], plugin::child_protocol::kRequestFd);
  posix_spawn_file_actions_adddup2(&actions, replies[1], plugin::child_protocol::kReplyFd);
  posix_spawn_file_actions_adddup2(&actions, lifeline[0], plugin::child_protocol::kLifelineFd);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);  // its own group, as ccdbench starts it
  posix_spawnattr_setpgroup(&attributes, 0);
  // PATH DIGEST N: no digest to check ("-"), no objects, the plugin's keys at their defaults (it has none).
  std::vector<std::string> arguments = {CCDBENCH_EXECUTABLE, plugin::kPluginHostCommand, plugin("broken_fork_at_load").string(), "-", "0"};
  std::vector<char*> argv;
  for (std::string& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  pid_t child = -1;
  ASSERT_EQ(::posix_spawn(&child, CCDBENCH_EXECUTABLE, &actions, &attributes, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  for (int fd : {requests[0], replies[1], lifeline[0]}) ::close(fd);
  // Its greeting: the plugin is loaded (and has forked).
  std::vector<char> greeting(plugin::child_protocol::kGreetingSize);
  std::size_t got = 0;
  for (ssize_t n = 1; got < greeting.size() && n > 0; got += static_cast<std::size_t>(std::max<ssize_t>(n, 0))) {
    n = ::read(replies[0], greeting.data() + got, greeting.size() - got);
  }
  ASSERT_EQ(got, greeting.size()) << "the child did not greet";
  ASSERT_EQ(forked().size(), 1u) << "the plugin did not fork at load";
  // Its requests end; the lifeline stays open (its parent is there), and nobody here kills its group.
  ::close(requests[1]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status)) << "it ended by itself, with a status of its own";
  ::close(replies[0]);
  ::close(lifeline[1]);
  expect_every_forked_process_gone("after the child ended with its parent there");
}

// A create that leaves the floating-point environment changed: refused in-process (exit 2); isolated, its first
// query used to be blamed and the run went on. One verdict now, either way.
TEST_F(Isolation, ACreateThatChangesTheFloatingPointEnvironmentIsRefusedInEitherMode) {
  for (const char* isolate : {":isolate=off", ":isolate=on"}) {
    const auto run =
        run_ccdbench("run --scene " + quoted(fold()) + " --max-steps 1 --strategy full+plugin:" + plugin("broken_create_rounding").string() +
                     isolate + " --out " + quoted(dir_ / "out"));
    EXPECT_EQ(run.exit_code, 2) << isolate << "\n" << run.output;
    EXPECT_NE(run.output.find("its create call failed: it left the floating-point environment changed"), std::string::npos) << isolate << "\n"
                                                                                                                            << run.output;
  }
}

// The memory a plugin takes is the cell's, wherever it runs: isolated, its child's peak is counted (it was 13.7 MiB
// isolated against 1,037 MiB in-process for a plugin that touches 1 GB).
TEST_F(Isolation, TheChildsMemoryIsCountedInTheCell) {
  const ScopedVariable size("CCDBENCH_TEST_TOUCH_MB", "512");
  std::map<std::string, double> peak;
  for (const char* isolate : {"off", "on"}) {
    const std::string spec = "full+plugin:" + plugin("broken_touch").string() + ":isolate=" + isolate;
    const auto [run, cells] = with_json("run --scene " + quoted(fold()) + " --max-steps 1 --strategy " + spec + " --out " + quoted(dir_ / "out"));
    ASSERT_EQ(run.exit_code, 0) << run.output;
    peak[isolate] = cell_of(cells, spec)["host_peak_bytes"].get<double>();
    if (std::string(isolate) == "on") {
      EXPECT_GE(cell_of(cells, spec).value("child_peak_bytes", 0.0), 512.0 * (1 << 20));
    }
  }
  ASSERT_GE(peak["off"], 512.0 * (1 << 20));
  EXPECT_NEAR(peak["on"], peak["off"], 0.1 * peak["off"]) << "isolated " << peak["on"] / (1 << 20) << " MiB, in-process " << peak["off"] / (1 << 20);
}

}  // namespace
}  // namespace ccd
