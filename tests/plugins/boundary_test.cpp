// The plugin boundary (docs/DESIGN.md §10): a user's CCD, however broken, never changes a verdict of anything else.
// Each test runs ccdbench as a user would, with a plugin broken on purpose (broken_plugin.cpp, wrapper_plugin.cpp),
// and checks that the harness's own answers are those of a run without it, and that what the plugin did is its error
// or ends the run saying so. Each guard it relies on can be built out (CCDBENCH_PLUGIN_GUARDS_OFF); a build without
// them fails these tests (scripts/guards-off.sh).

#include "datasets/procedural_scenes.hpp"
#include "tests/plugins/plugin_runs.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
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
using testing::without_segv_reports;

/// The extremes suite's families where flush-to-zero and the rounding mode change answers (subnormal and tiny
/// coordinates), and one where they do not.
constexpr const char* kFloatingPointFamilies = "subnormal,smallest-normal,scaled-2^-1000,scaled-2^-960,zero-motion";

class Boundary : public testing::PluginRuns {
 protected:
  /// The extremes suite as query files with the reference's labels (subnormal, tiny and huge coordinates: where the
  /// floating-point environment matters), written by a process that loaded no plugin.
  std::filesystem::path extremes() {
    const std::filesystem::path folder = dir_ / "extremes";
    if (!std::filesystem::exists(folder)) {
      const auto written = run_ccdbench("stress --family " + std::string(kFloatingPointFamilies) + " --write-queries " + quoted(folder));
      EXPECT_EQ(written.exit_code, 0) << written.output;
    }
    return folder;
  }

  /// Every step's answers digest of the built-in cells (`full`, `full+cubic64`) of a run's results.jsonl, by scene, δ,
  /// strategy and step; and the colliding count of each (the truth).
  static std::map<std::string, std::string> built_in_answers(const std::filesystem::path& out) {
    std::map<std::string, std::string> answers;
    for (const nlohmann::json& record : testing::read_json_lines(out / "results.jsonl")) {
      if (record.value("record", "") != "step") continue;
      const std::string strategy = record["strategy"];
      if (strategy.find("plugin:") != std::string::npos) continue;
      std::ostringstream key;
      key << record["scene"].get<std::string>() << " δ " << record["thickness"].dump() << " " << strategy << " step " << record["step"];
      answers[key.str()] = record["answers"].get<std::string>() + " colliding " + record["colliding"].dump();
    }
    return answers;
  }

  /// The lines of an answer file (--write-answers) of methods whose name starts with one of `heads`.
  static std::vector<std::string> answer_lines(const std::filesystem::path& file, const std::vector<std::string>& heads) {
    std::vector<std::string> kept;
    std::istringstream lines(text_of(file));
    for (std::string line; std::getline(lines, line);) {
      std::vector<std::string> fields;
      std::istringstream split(line);
      for (std::string field; std::getline(split, field, ',');) fields.push_back(field);
      if (fields.size() < 3) continue;
      for (const std::string& head : heads) {
        if (fields[2].rfind(head, 0) == 0) kept.push_back(line);
      }
    }
    return kept;
  }
};

// A plugin built with -Ofast sets flush-to-zero and denormals-are-zero when it is loaded (crtfastmath.o). Loaded
// first, before the reference and a conservative narrow phase, it changes none of their answers: its load's
// environment is its calls' alone, and the records name it.
TEST_F(Boundary, APluginBuiltWithFastMathChangesNoAnswerOfTheReferenceOrTheBuiltIns) {
  const std::string queries = "queries " + quoted(extremes()) + " --faults " + quoted(dir_ / "faults") + " --toi --write-answers ";
  const auto clean = run_ccdbench(queries + quoted(dir_ / "clean.csv") + " --method exact,conservative");
  ASSERT_EQ(clean.exit_code, 0) << clean.output;
  const auto loaded = run_ccdbench(queries + quoted(dir_ / "loaded.csv") + " --in-process --method plugin:" + plugin("broken_ofast").string() +
                                   ",exact,conservative");
  ASSERT_EQ(loaded.exit_code, 0) << loaded.output;
  const std::vector<std::string> expected = answer_lines(dir_ / "clean.csv", {"exact", "conservative"});
  ASSERT_GT(expected.size(), 100u);
  EXPECT_EQ(answer_lines(dir_ / "loaded.csv", {"exact", "conservative"}), expected) << "the reference or conservative answered otherwise";

  // The stress table, at δ = 0 and each case's δ > 0: the reference labels and conservative's rows are the same.
  const std::string families = " --family " + std::string(kFloatingPointFamilies);
  const auto [stress_clean, rows_clean] = with_json("stress --method conservative" + families);
  const auto [stress_loaded, rows_loaded] =
      with_json("stress --in-process --method plugin:" + plugin("broken_ofast").string() + ",conservative" + families);
  ASSERT_EQ(stress_loaded.exit_code, 0) << stress_loaded.output;
  nlohmann::json conservative_rows = nlohmann::json::array();
  for (const nlohmann::json& row : rows_loaded) {
    if (row["method"].get<std::string>().rfind("conservative", 0) == 0) conservative_rows.push_back(row);
  }
  EXPECT_EQ(conservative_rows, rows_clean);

  // In a run, every record says what its load did, and the built-in cells answer as without it.
  const auto [run, summaries] =
      with_json("run --scene " + quoted(fold()) + " --in-process --strategy plugin:" + plugin("broken_ofast").string() + ",full");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json cell = cell_of(summaries, "plugin:" + plugin("broken_ofast").string());
  EXPECT_NE(cell["provenance"].value("plugin_environment_at_load", "").find("flush-to-zero on"), std::string::npos) << cell["provenance"];
}

// A call that leaves the rounding mode changed is that call's error, named; nothing after it runs in that mode. The
// same verdict isolated: its child holds each call to what an in-process call is held to.
TEST_F(Boundary, ACallThatLeavesTheRoundingModeChangedIsThatCallsError) {
  const std::string queries = "queries " + quoted(extremes()) + " --faults " + quoted(dir_ / "faults") + " --toi --write-answers ";
  ASSERT_EQ(run_ccdbench(queries + quoted(dir_ / "clean.csv") + " --method exact,conservative").exit_code, 0);
  const std::string rounding = "plugin:" + plugin("broken_rounding").string();
  for (const char* where : {" --in-process", " --isolate"}) {
    SCOPED_TRACE(where);
    const auto loaded = run_ccdbench(queries + quoted(dir_ / "loaded.csv") + where + " --json " + quoted(dir_ / "scores.json") + " --method " +
                                     rounding + ",exact," + rounding + ":errors=hit,conservative");
    ASSERT_EQ(loaded.exit_code, 0) << loaded.output;
    EXPECT_EQ(answer_lines(dir_ / "loaded.csv", {"exact", "conservative"}), answer_lines(dir_ / "clean.csv", {"exact", "conservative"}));
    for (const nlohmann::json& score : read_json(dir_ / "scores.json")) {
      if (score["file"] != "(all)" || score["method"].get<std::string>().rfind("plugin:", 0) != 0) continue;
      EXPECT_GT(score["queries"].get<int>(), 100);
      EXPECT_EQ(score["errors"], score["queries"]) << "every call left the rounding mode upward";
    }
    EXPECT_NE(loaded.output.find("it left the floating-point environment changed: rounding to nearest -> upward"), std::string::npos)
        << loaded.output;
  }
}

// A whole-step plugin that writes through the const pointers it is given changes no frame of the run: a later
// built-in cell answers as in a run without it.
TEST_F(Boundary, APluginThatWritesItsInputsChangesNoFrameOfTheRun) {
  const std::string scene = "run --scene " + quoted(fold()) + " --thickness 0 --out ";
  const auto [clean, clean_cells] = with_json(scene + quoted(dir_ / "clean") + " --strategy full");
  ASSERT_EQ(clean.exit_code, 0) << clean.output;
  const auto [dirty, cells] =
      with_json(scene + quoted(dir_ / "dirty") + " --in-process --strategy plugin:" + plugin("broken_writes_inputs").string() + ",full");
  ASSERT_EQ(dirty.exit_code, 0) << dirty.output;
  ASSERT_GT(cell_of(cells, "full")["colliding"].get<int>(), 0);
  EXPECT_EQ(cell_of(cells, "full")["missed"], 0) << dirty.output;
  EXPECT_EQ(built_in_answers(dir_ / "dirty"), built_in_answers(dir_ / "clean"));
}

// exit(0) inside a call, in-process: the run ends with status 1 and a message naming the plugin, the call and the
// cell (it used to end with status 0, no table and no word); the cells finished before are kept. Isolated, it is that
// call's error and the run goes on.
TEST_F(Boundary, AnExitInsideACallEndsTheRunSayingSoOrIsTheCallsErrorIsolated) {
  // Every way out: exit, abort, a failed assert, and errx (the C library's own exit, which no symbol interposes).
  for (const auto& [name, said] : {std::pair{"broken_exit_on_3", "called exit(0) during a"},
                                   {"broken_abort_on_3", "called abort() during a"},
                                   {"broken_assert_on_3", "failed an assertion ("},
                                   {"broken_errx_on_3", "ended the process (through the C library's exit)"}}) {
    SCOPED_TRACE(name);
    const std::string ending = "full+plugin:" + plugin(name).string();
    const std::filesystem::path out = dir_ / (std::string("in-process-") + name);
    const auto in_process = run_ccdbench("run --scene " + quoted(fold()) + " --max-steps 2 --in-process --strategy full," + ending +
                                         ",full+cubic64 --out " + quoted(out));
    EXPECT_EQ(in_process.exit_code, 1) << in_process.output;
    EXPECT_NE(in_process.output.find(said), std::string::npos) << in_process.output;
    EXPECT_NE(in_process.output.find("cell fold8 / full+plugin:lib" + std::string(name) + ".so"), std::string::npos) << in_process.output;
    std::size_t kept = 0;
    for (const auto& entry : std::filesystem::directory_iterator(out / "cells")) kept += entry.path().extension() == ".json";
    EXPECT_EQ(kept, 1u) << "the cell of full, finished before, is kept";
  }
  const std::string exiting = "full+plugin:" + plugin("broken_exit_on_3").string();
  // One step: the plugin's process ends every third query, and each restart is a new ccdbench process.
  const std::string run = "run --scene " + quoted(fold()) + " --max-steps 1 --strategy full," + exiting + ",full+cubic64 --out ";

  const auto [isolated, summaries] = with_json(run + quoted(dir_ / "isolated") + " --isolate");
  ASSERT_EQ(isolated.exit_code, 0) << isolated.output;
  EXPECT_GT(cell_of(summaries, exiting)["errors"].get<int>(), 0);
  EXPECT_EQ(cell_of(summaries, "full+cubic64")["errors"], 0);
}

// In-process, chdir inside a call is refused (the call's error), and outputs named relative to the working directory
// land there (isolated, the child's working directory is its own).
TEST_F(Boundary, AChdirInsideACallIsRefusedAndEveryOutputLandsWhereItWasNamed) {
  const std::filesystem::path work = dir_ / "work", elsewhere = dir_ / "elsewhere";
  std::filesystem::create_directories(work);
  std::filesystem::create_directories(elsewhere);
  const ScopedVariable moving("CCDBENCH_TEST_CHDIR", elsewhere.string());
  const std::string chdir = "full+plugin:" + plugin("broken_chdir").string();
  const auto run = run_ccdbench(
      "run --scene " + quoted(fold()) + " --in-process --max-steps 2 --strategy full," + chdir + " --out out --json r.json --report report", work);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_TRUE(std::filesystem::exists(work / "r.json"));
  EXPECT_TRUE(std::filesystem::exists(work / "out" / "results.jsonl"));
  EXPECT_TRUE(std::filesystem::exists(work / "report" / "README.md"));
  EXPECT_TRUE(std::filesystem::is_empty(elsewhere)) << "an output followed the plugin's chdir";
  if (!std::filesystem::exists(work / "r.json")) return;
  const nlohmann::json cell = cell_of(read_json(work / "r.json"), chdir);
  EXPECT_GT(cell["errors"].get<int>(), 0);
  EXPECT_NEAR(cell["errors"].get<double>(), cell["elementary_tests"].get<double>() * cell["steps"].get<double>(), 0.5) << "every call tried";
  const std::string faults = text_of(std::filesystem::path(cell.value("errors_written", "")) / "FAULTS.txt");
  EXPECT_NE(faults.find("it called chdir(\"" + elsewhere.string() + "\")"), std::string::npos) << faults;
}

// In-process, a call that never returns ends the run after its timeout, naming the plugin, the call and the cell (it
// used to hang the run forever, its progress line naming the cell before).
TEST_F(Boundary, ACallPastItsTimeoutEndsAnInProcessRunNamingIt) {
  const auto start = std::chrono::steady_clock::now();
  const auto run = testing::run_command("timeout 30 " + std::string(CCDBENCH_EXECUTABLE) + " run --scene " + quoted(fold()) +
                                        " --strategy full,full+plugin:" + plugin("broken_hang_on_3").string() + ":isolate=off:timeout=0.5 --out " +
                                        quoted(dir_ / "out"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(25));
  EXPECT_NE(run.output.find("did not return within its timeout of 0.5 s during cell fold8 / full+plugin:libbroken_hang_on_3.so"), std::string::npos)
      << run.output;
}

// A plugin is its file and every library it brings in, as loaded: rebuilding the library a wrapper links makes it
// another plugin, whose cells are computed, never taken from the other build's.
TEST_F(Boundary, RebuildingALibraryThePluginLinksMakesItAnotherPlugin) {
  for (const char* isolate : {":isolate=off", ":isolate=on"}) {
    SCOPED_TRACE(isolate);
    const std::filesystem::path out = dir_ / (std::string("out") + isolate);
    const std::string spec = "full+plugin:" + wrapper(1).string() + isolate;
    const std::string run = "run --scene " + quoted(fold()) + " --thickness 0 --out " + quoted(out) + " --strategy " + spec;
    const auto [first, before] = with_json(run);
    ASSERT_EQ(first.exit_code, 0) << first.output;
    ASSERT_GT(cell_of(before, spec)["colliding"].get<int>(), 0);
    EXPECT_EQ(cell_of(before, spec)["missed"], 0) << "this build finds every contact";
    EXPECT_NE(cell_of(before, spec)["provenance"].value("plugin_objects", "").find("libbroken_dependency.so"), std::string::npos)
        << "the library is part of the plugin's code";
    wrapper(0);  // the library rebuilt: it finds nothing now, the wrapper's file unchanged
    const auto [second, after] = with_json(run);
    ASSERT_EQ(second.exit_code, 0) << second.output;
    const nlohmann::json cell = cell_of(after, spec);
    EXPECT_FALSE(cell.value("resumed", false)) << "a cell of the other build of its library was reused";
    EXPECT_EQ(cell["missed"], cell["colliding"]) << second.output;
    EXPECT_NE(cell["strategy"], cell_of(before, spec)["strategy"]) << "the same digest for different code";
  }
}

// A plugin file replaced during a run (an isolated child started after a crash would load the new file): the new
// code's answers are never taken under the digest the run began with; every request after the change is an error.
TEST_F(Boundary, AFileReplacedDuringARunGivesNoAnswersUnderTheOldDigest) {
  const std::filesystem::path replacing = copy_of("broken_replace_self_on_3", "libreplacing.so");
  const ScopedVariable replacement("CCDBENCH_TEST_REPLACEMENT", plugin("naive_float").string());
  const auto [run, scores] =
      with_json("queries " + quoted(extremes()) + " --faults " + quoted(dir_ / "faults") + " --method plugin:" + replacing.string() + ":isolate=on");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  nlohmann::json total;
  for (const nlohmann::json& score : scores) {
    if (score["file"] == "(all)") total = score;
  }
  ASSERT_GT(total["queries"].get<int>(), 10);
  EXPECT_EQ(total["errors"].get<int>(), total["queries"].get<int>() - 2) << "two answers before the change; none of the other code after it";
  EXPECT_NE(run.output.find("its code changed during the run"), std::string::npos) << run.output;
}

// An answer file, or a folder of them, rewritten while ccdbench reads it (tests/plugins/rewrite_injection.cpp
// rewrites it before its second open): the verdict and the digest come from one read, so the digest in the result
// is that of the answers judged.
TEST_F(Boundary, AnswersRewrittenWhileReadPutNoOtherDigestOnTheirVerdict) {
  const std::string queries = "queries " + quoted(extremes());
  ASSERT_EQ(run_ccdbench(queries + " --method cubic64 --write-answers " + quoted(dir_ / "a.csv")).exit_code, 0);
  ASSERT_EQ(run_ccdbench(queries + " --method cubic32 --write-answers " + quoted(dir_ / "b.csv")).exit_code, 0);
  std::filesystem::copy_file(dir_ / "a.csv", dir_ / "a-copy.csv");
  auto digest_of = [](const std::string& output) {
    const std::size_t at = output.find(":digest=");
    return at == std::string::npos ? std::string() : output.substr(at + 8, 32);
  };
  const auto clean = run_ccdbench(queries + " --method answers:" + (dir_ / "a-copy.csv").string());
  ASSERT_EQ(clean.exit_code, 0) << clean.output;
  const std::string injection = "ASAN_OPTIONS=verify_asan_link_order=0 LD_PRELOAD=" + quoted(plugin("ccd_rewrite_injection")) + " ";
  {
    const ScopedVariable path("CCDBENCH_REWRITE_PATH", (dir_ / "a.csv").string());
    const ScopedVariable with("CCDBENCH_REWRITE_WITH", (dir_ / "b.csv").string());
    const auto rewritten = testing::run_command(injection + CCDBENCH_EXECUTABLE + " " + queries + " --method answers:" + (dir_ / "a.csv").string());
    ASSERT_EQ(rewritten.exit_code, 0) << rewritten.output;
    EXPECT_EQ(digest_of(rewritten.output), digest_of(clean.output)) << "the digest of other bytes than those scored";
  }
  // A folder of step answers: its files rewritten between two reads.
  const std::string scene = "run --scene " + quoted(fold()) + " --thickness 0 --strategy ";
  ASSERT_EQ(run_ccdbench(scene + "full,full+cubic32 --out " + quoted(dir_ / "written") + " --write-answers " + quoted(dir_ / "answers")).exit_code,
            0);
  const std::filesystem::path step = dir_ / "answers" / "full" / "fold8" / "step_0003.csv";
  ASSERT_TRUE(std::filesystem::exists(step));
  const auto [plain, plain_cells] = with_json(scene + "answers:" + (dir_ / "answers" / "full").string() + " --out " + quoted(dir_ / "plain"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  const ScopedVariable path("CCDBENCH_REWRITE_PATH", step.string());
  const ScopedVariable with("CCDBENCH_REWRITE_WITH", (dir_ / "answers" / "full+cubic32" / "fold8" / "step_0003.csv").string());
  const std::filesystem::path json = dir_ / "rewritten.json";
  const auto rewritten = testing::run_command(injection + CCDBENCH_EXECUTABLE + " " + scene + "answers:" + (dir_ / "answers" / "full").string() +
                                              " --out " + quoted(dir_ / "rewritten") + " --json " + quoted(json));
  ASSERT_EQ(rewritten.exit_code, 0) << rewritten.output;
  // Read once: the digest and the verdict are both those of the folder as first read.
  const nlohmann::json judged = read_json(json).at(0), expected = plain_cells.at(0);
  EXPECT_EQ(judged["strategy"], expected["strategy"]) << "the digest of other bytes than those judged";
  for (const char* field : {"missed", "false_alarms", "reported"}) EXPECT_EQ(judged[field], expected[field]) << field;
}

/// The children of `pid` that are still running (not zombies).
std::vector<pid_t> children_of(pid_t pid) {
  std::vector<pid_t> found;
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::istringstream stat(text_of(entry.path() / "stat"));
    std::string skip, state;
    pid_t ppid = 0;
    std::getline(stat, skip, ')');
    stat >> state >> ppid;
    if (ppid == pid && state != "Z") found.push_back(std::stoi(name));
  }
  return found;
}

/// Starts `ccdbench ARGUMENTS...`, waits until it has one child (a plugin's, hanging), kills it with SIGKILL, and says
/// whether that child was gone within ten seconds (killed then, if not).
::testing::AssertionResult child_dies_with_its_parent(std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), CCDBENCH_EXECUTABLE);
  std::vector<char*> argv;
  for (std::string& argument : arguments) argv.push_back(argument.data());
  argv.push_back(nullptr);
  pid_t parent = -1;
  if (::posix_spawn(&parent, CCDBENCH_EXECUTABLE, nullptr, nullptr, argv.data(), environ) != 0) return ::testing::AssertionFailure() << "no ccdbench";
  std::vector<pid_t> children;
  for (int tries = 0; tries < 300 && children.empty(); ++tries) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    children = children_of(parent);
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));  // a describing child that loads quickly is gone by then
  children = children_of(parent);
  ::kill(parent, SIGKILL);
  int status = 0;
  ::waitpid(parent, &status, 0);
  if (children.size() != 1) return ::testing::AssertionFailure() << children.size() << " children, not the one hanging";
  const pid_t child = children.front();
  for (int tries = 0; tries < 100; ++tries) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const std::string stat = text_of("/proc/" + std::to_string(child) + "/stat");
    if (stat.empty() || stat.find(") Z") != std::string::npos) return ::testing::AssertionSuccess();
  }
  ::kill(child, SIGKILL);
  return ::testing::AssertionFailure() << "child " << child << " still ran ten seconds after its parent was killed";
}

// Two folders of answers that differ are two digests, whatever their files hold: names and bytes are each counted by
// their length (a digest of "name NUL bytes NUL" made a folder with a NUL in a comment line the twin of another).
TEST_F(Boundary, FoldersOfAnswersThatDifferHaveDifferentDigests) {
  const std::string scene = "run --scene " + quoted(fold()) + " --thickness 0 --max-steps 2 --strategy ";
  ASSERT_EQ(run_ccdbench(scene + "full --out " + quoted(dir_ / "written") + " --write-answers " + quoted(dir_ / "answers")).exit_code, 0);
  const std::filesystem::path whole = dir_ / "answers" / "full", hiding = dir_ / "hiding";
  std::filesystem::copy(whole, hiding, std::filesystem::copy_options::recursive);
  const std::string step = text_of(whole / "fold8" / "step_0001.csv");
  ASSERT_FALSE(step.empty());
  const std::string nul(1, '\0');
  // whole: its steps, and a file "step_0001.csu" of "#<NUL>fold8/step_0001.csv<NUL>#"; hiding: "step_0001.csu" of "#"
  // and its step 1 behind "#<NUL>fold8/step_0001.csv<NUL>" (its first pair in a comment). The old stream was the same.
  testing::write_text(whole / "fold8" / "step_0001.csu", "#" + nul + "fold8/step_0001.csv" + nul + "#");
  testing::write_text(hiding / "fold8" / "step_0001.csu", "#");
  testing::write_text(hiding / "fold8" / "step_0001.csv", "#" + nul + "fold8/step_0001.csv" + nul + step);
  auto digest_of = [&](const std::filesystem::path& folder) {
    const auto run = run_ccdbench(scene + "answers:" + folder.string() + " --out " + quoted(dir_ / ("out-" + folder.filename().string())));
    const std::size_t at = run.output.find(":digest=");
    return at == std::string::npos ? run.output : run.output.substr(at + 8, 32);
  };
  EXPECT_NE(digest_of(whole), digest_of(hiding));
}

// A child dies with its parent: killed while its plugin hangs in a call, or while it hangs being loaded (its
// constructor holds the dynamic loader's lock then), the parent leaves no child running.
TEST_F(Boundary, AChildDiesWithItsParentEvenWhileThePluginHangs) {
  EXPECT_TRUE(child_dies_with_its_parent({"queries", extremes().string(), "--method",
                                          "plugin:" + plugin("broken_hang_on_3").string() + ":isolate=on:timeout=600", "--faults",
                                          (dir_ / "faults").string()}))
      << "hanging in a call";
  EXPECT_TRUE(child_dies_with_its_parent({"strategies", "--plugin", plugin("broken_hang_at_load").string()})) << "hanging at load";
}

// Errors are part of what two passes must agree on: a plugin whose later answers are errors where its first were
// "apart" reports the same pairs (errors=miss), yet its cell is not deterministic.
TEST_F(Boundary, ErrorsThatAppearInALaterPassAreNondeterminism) {
  const std::string spec = "full+plugin:" + plugin("broken_errors_later").string() + ":isolate=off";
  const auto [run, summaries] = with_json("run --scene " + quoted(fold()) + " --repeat 2 --strategy " + spec + " --out " + quoted(dir_ / "out"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json cell = cell_of(summaries, spec);
  EXPECT_EQ(cell.value("nondeterministic_at_step", nlohmann::json()), 0) << run.output;
}

// Answers that depend on what the plugin was asked before differ between two passes of the same steps: the cell says
// so in the table and the JSON, and the gate fails it unless its entry allows it, though it misses nothing.
TEST_F(Boundary, AnswersThatChangeBetweenPassesAreAVerdictTheGateSees) {
  // In-process: its count goes on from pass to pass (a fresh child for each pass would count from 0 again).
  const std::string spec = "full+plugin:" + plugin("broken_first_calls").string() + ":isolate=off";
  const auto [run, summaries] = with_json("run --scene " + quoted(fold()) + " --repeat 2 --strategy " + spec + " --out " + quoted(dir_ / "out"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json cell = cell_of(summaries, spec);
  ASSERT_GT(cell["colliding"].get<int>(), 0);
  EXPECT_EQ(cell["missed"], 0) << "it misses nothing: a gate on misses alone would pass it";
  EXPECT_TRUE(cell.contains("nondeterministic_at_step")) << run.output;
  EXPECT_NE(run.output.find("answers changed between passes at step"), std::string::npos) << run.output;
  std::ofstream(dir_ / "results.json") << summaries.dump();
  nlohmann::json entry = {{"scene", cell["scene"]}, {"strategy", spec}, {"thickness", "scene"}, {"max_missed", 0}};
  std::ofstream(dir_ / "baseline.json") << nlohmann::json::array({entry}).dump();
  const auto gate = run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "results.json"));
  EXPECT_EQ(gate.exit_code, 1) << gate.output;
  entry["allow_nondeterministic"] = true;
  std::ofstream(dir_ / "baseline.json") << nlohmann::json::array({entry}).dump();
  EXPECT_EQ(run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "results.json")).exit_code, 0);
}

// A plugin that crashed on every 17th query, its errors counted as hits (errors=hit), misses nothing: the gate fails
// it all the same, on its errors.
TEST_F(Boundary, ErrorsCountedAsHitsStillFailTheGate) {
  const std::string spec = "full+plugin:" + plugin("broken_crash_on_17").string() + ":isolate=on:errors=hit";
  const ScopedVariable quiet("ASAN_OPTIONS", without_segv_reports());  // the children's crashes are the input here
  const auto [run, summaries] = with_json("run --scene " + quoted(fold()) + " --max-steps 3 --strategy " + spec + " --out " + quoted(dir_ / "out"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json cell = cell_of(summaries, spec);
  ASSERT_GT(cell["colliding"].get<int>(), 0);
  EXPECT_EQ(cell["missed"], 0);
  EXPECT_GT(cell["errors"].get<int>(), 0);
  std::ofstream(dir_ / "results.json") << summaries.dump();
  std::ofstream(dir_ / "baseline.json")
      << nlohmann::json::array({{{"scene", cell["scene"]}, {"strategy", spec}, {"thickness", "scene"}, {"max_missed", 0}}}).dump();
  const auto gate = run_ccdbench("check --baseline " + quoted(dir_ / "baseline.json") + " " + quoted(dir_ / "results.json"));
  EXPECT_EQ(gate.exit_code, 1) << gate.output;
  EXPECT_NE(gate.output.find("answers could not be taken"), std::string::npos) << gate.output;
}

// A plugin whose load crashes (a constructor that dereferences null) is refused as that plugin's error, exit 2, with
// or without isolation: this process never loads it to find out (it used to end with the plugin's signal, 139).
TEST_F(Boundary, APluginWhoseLoadCrashesIsRefusedNotTheRunsCrash) {
  const ScopedVariable quiet("ASAN_OPTIONS", without_segv_reports());
  for (const char* isolate : {" --in-process", " --isolate"}) {
    const auto run = run_ccdbench("run --scene " + quoted(fold()) + " --strategy full,full+plugin:" + plugin("broken_crash_at_load").string() +
                                  " --out " + quoted(dir_ / "out") + isolate);
    EXPECT_EQ(run.exit_code, 2) << isolate << run.output;
    EXPECT_NE(run.output.find("libbroken_crash_at_load.so: its child process ended while loading it (it crashed with signal 11"), std::string::npos)
        << run.output;
  }
}

// Every broken plugin runs before and between the built-ins and the exact reference, at the scene's δ and at 0, once
// in-process and once isolated: in `run`, full and full+cubic64 (the truth computed afresh beside the plugins, a cache
// of its own for each run) answer every step as in a run without any plugin; in `queries`, exact, conservative and
// cubic64 answer every query as without them. In-process, the plugins that end the process (exit, a hang) are left
// out: ending the run is what in-process promises for them (the tests above).
TEST_F(Boundary, EveryBrokenPluginBesideTheBuiltInsChangesNoneOfTheirAnswers) {
  const std::filesystem::path elsewhere = dir_ / "elsewhere";
  std::filesystem::create_directories(elsewhere);
  const ScopedVariable moving("CCDBENCH_TEST_CHDIR", elsewhere.string());
  const ScopedVariable quiet("ASAN_OPTIONS", without_segv_reports());
  const ScopedVariable replacement("CCDBENCH_TEST_REPLACEMENT", plugin("naive_float").string());
  auto p = [](const std::string& name) { return "plugin:" + plugin(name).string(); };
  // Two steps: the plugins that end their process every few queries restart it hundreds of times a step, each a new
  // ccdbench process (most of this test's time, under ASan most of all).
  const std::string scene = "run --scene " + quoted(fold()) + " --max-steps 2 --thickness scene,0 --out ";
  auto run_with_cache = [&](const std::string& name, const std::string& arguments) {
    const ScopedVariable cache("CCDBENCH_CACHE_DIR", (dir_ / ("cache-" + name)).string());
    return run_ccdbench(scene + quoted(dir_ / name) + " " + arguments);
  };
  ASSERT_EQ(run_with_cache("clean", "--strategy full,full+cubic64").exit_code, 0);
  const std::map<std::string, std::string> expected = built_in_answers(dir_ / "clean");
  ASSERT_EQ(expected.size(), 2u * 2u * 2u) << "two built-in cells at two δ, two steps each";
  ASSERT_TRUE(std::any_of(expected.begin(), expected.end(), [](const auto& step) { return step.second.find(" colliding 0") == std::string::npos; }))
      << "no step collides: the answers compared would prove nothing";
  const std::string broken = p("broken_ofast") + ",full+" + p("broken_rounding") + ",full," + p("broken_writes_inputs") + ",full+" +
                             p("broken_chdir") + ",full+cubic64,full+" + p("broken_first_calls") + ",full+plugin:" + wrapper(1).string();
  const auto in_process = run_with_cache("in-process", "--in-process --strategy " + broken);
  ASSERT_EQ(in_process.exit_code, 0) << in_process.output;
  EXPECT_EQ(built_in_answers(dir_ / "in-process"), expected);
  const std::string replacing = "full+plugin:" + copy_of("broken_replace_self_on_3", "libreplacing.so").string();
  const auto isolated = run_with_cache(
      "isolated", "--isolate --strategy " + broken + "," + p("broken_exit_on_3") + ",full+" + p("broken_crash_on_17") + "," + replacing);
  ASSERT_EQ(isolated.exit_code, 0) << isolated.output;
  EXPECT_EQ(built_in_answers(dir_ / "isolated"), expected);

  // queries: the query plugins first and between the reference and the narrow phases.
  const std::string queries = "queries " + quoted(extremes()) + " --faults " + quoted(dir_ / "faults") + " --toi --write-answers ";
  const std::vector<std::string> built_ins = {"exact", "conservative", "cubic64"};
  ASSERT_EQ(run_ccdbench(queries + quoted(dir_ / "clean.csv") + " --method exact,conservative,cubic64").exit_code, 0);
  const std::string before = p("broken_ofast") + "," + p("broken_rounding") + "," + p("broken_writes_inputs");
  const std::string between = p("broken_chdir") + "," + p("broken_first_calls") + ",plugin:" + wrapper(1).string();
  for (const char* where : {"--in-process", "--isolate"}) {
    SCOPED_TRACE(where);
    const std::string extra = std::string(where) == "--isolate" ? "," + p("broken_exit_on_3") + "," + p("broken_crash_on_17") : "";
    const auto loaded = run_ccdbench(queries + quoted(dir_ / "loaded.csv") + " " + where + " --method " + before + ",exact," + between +
                                     ",conservative" + extra + ",cubic64");
    ASSERT_EQ(loaded.exit_code, 0) << loaded.output;
    EXPECT_EQ(answer_lines(dir_ / "loaded.csv", built_ins), answer_lines(dir_ / "clean.csv", built_ins));
  }
}

}  // namespace
}  // namespace ccd
