// Answer folders read in bounded memory (docs/DESIGN.md §10 "Identity", docs/audit.md "Answer files"): `answers:DIR` reads
// the step files of its scenes and nothing else, each a regular file (or a link to one) read no further than its
// size, and every path that should be a step file and is not one says what it is.

#include "tests/plugins/plugin_runs.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <functional>

extern char** environ;

namespace ccd {
namespace {

using testing::quoted;
using testing::run_ccdbench;

class AnswerFolders : public testing::PluginRuns {
 protected:
  void SetUp() override {
    PluginRuns::SetUp();
    const auto written = run_ccdbench("run --scene " + quoted(fold()) + " --thickness 0 --max-steps 3 --strategy full --out " +
                                      quoted(dir_ / "written") + " --write-answers " + quoted(dir_ / "answers"));
    ASSERT_EQ(written.exit_code, 0) << written.output;
    ASSERT_TRUE(std::filesystem::exists(steps() / "step_0002.csv"));
  }
  /// The scene's step files, as --write-answers wrote them.
  std::filesystem::path steps() const { return dir_ / "answers" / "full" / "fold8"; }

  /// `ccdbench run` judging the answer folder (fresh), through the shell.
  testing::CommandResult judge() {
    return run_ccdbench("run --scene " + quoted(fold()) + " --thickness 0 --max-steps 3 --fresh --out " + quoted(dir_ / "judged") + " --answers " +
                        quoted(dir_ / "answers" / "full"));
  }

  /// The same run started directly: its exit status and its peak resident memory in bytes (wait4's ru_maxrss).
  std::pair<int, long> judged_peak() {
    std::vector<std::string> arguments = {CCDBENCH_EXECUTABLE,
                                          "run",
                                          "--scene",
                                          fold().string(),
                                          "--thickness",
                                          "0",
                                          "--max-steps",
                                          "3",
                                          "--fresh",
                                          "--out",
                                          (dir_ / "judged").string(),
                                          "--answers",
                                          (dir_ / "answers" / "full").string()};
    std::vector<char*> argv;
    for (std::string& argument : arguments) argv.push_back(argument.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t quiet;
    posix_spawn_file_actions_init(&quiet);
    posix_spawn_file_actions_addopen(&quiet, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&quiet, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
    pid_t pid = -1;
    const int spawned = ::posix_spawn(&pid, CCDBENCH_EXECUTABLE, &quiet, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&quiet);
    if (spawned != 0) return {-1, 0};
    int status = 0;
    rusage usage{};
    ::wait4(pid, &status, 0, &usage);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, usage.ru_maxrss * 1024};
  }
};

// A 2 GB file beside the step files (a core dump, a log) was read whole before any check: 5.9 GB and 129 s for one of
// 1.5 GB. It is not a step file, so it is not read at all.
TEST_F(AnswerFolders, AJunkFileBesideTheStepsIsNotRead) {
  const auto [clean_status, clean_peak] = judged_peak();
  ASSERT_EQ(clean_status, 0);
  {
    std::ofstream junk(steps() / "core", std::ios::binary);
    junk.seekp((std::streamoff{2} << 30) - 1);
    junk.put('\n');  // sparse: 2 GB of zeros that take no disk
  }
  ASSERT_EQ(std::filesystem::file_size(steps() / "core"), std::uintmax_t{2} << 30);
  const auto [status, peak] = judged_peak();
  EXPECT_EQ(status, 0);
  EXPECT_LT(peak - clean_peak, 64L << 20) << "peak " << (peak >> 20) << " MiB with the junk file, " << (clean_peak >> 20) << " MiB without";
}

// Each thing in the place of a step file says what it is, as FILE: REASON, exit 2; a link to a regular file is read as
// the file (and a scene folder that is a link, as the folder).
TEST_F(AnswerFolders, EachStepFileThatIsNoFileSaysWhatItIs) {
  const std::filesystem::path step = steps() / "step_0001.csv", kept = dir_ / "step_0001.csv";
  std::filesystem::rename(step, kept);
  std::filesystem::create_symlink(kept, step);
  const auto linked = judge();
  EXPECT_EQ(linked.exit_code, 0) << "a link to a step file is that file: " << linked.output;
  std::filesystem::remove(step);
  const std::filesystem::path scene = dir_ / "scene-folder";
  std::filesystem::rename(steps(), scene);
  std::filesystem::create_directory_symlink(scene, steps());
  std::filesystem::copy_file(kept, scene / "step_0001.csv");
  const auto linked_scene = judge();
  EXPECT_EQ(linked_scene.exit_code, 0) << "a scene folder that is a link is that folder: " << linked_scene.output;
  std::filesystem::remove(scene / "step_0001.csv");

  struct Case {
    const char* what;
    std::function<void()> make;
    const char* says;
  };
  const std::vector<Case> cases = {
      {"FIFO", [&] { ASSERT_EQ(::mkfifo(step.c_str(), 0600), 0); }, "step_0001.csv: is a FIFO (named pipe), not a step file (a regular file)"},
      {"/dev/zero", [&] { std::filesystem::create_symlink("/dev/zero", step); },
       "step_0001.csv: is a link to a character device, not to a step file"},
      {"folder", [&] { std::filesystem::create_directory(step); }, "step_0001.csv: is a folder, not a step file (a regular file)"},
      {"loop", [&] { std::filesystem::create_symlink(step, step); }, "step_0001.csv: is a link in a loop of links, not a step file"},
      {"dangling link", [&] { std::filesystem::create_symlink(dir_ / "nowhere.csv", step); }, "nowhere.csv, which does not exist"}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    std::filesystem::remove_all(step);
    c.make();
    const auto refused = judge();
    EXPECT_EQ(refused.exit_code, 2) << refused.output;
    EXPECT_NE(refused.output.find(c.says), std::string::npos) << refused.output;
    EXPECT_LT(refused.output.size(), 4000u) << "a message a person can read";
  }
  std::filesystem::remove_all(step);
}

}  // namespace
}  // namespace ccd
