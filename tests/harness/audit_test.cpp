// Auditing a CCD as its users do (docs/audit.md): isolation by default and cheap, and each defect a real
// audit found in the harness, fixed. Every test runs ccdbench as a user would, without the public data.

#include "ccd/config.hpp"
#include "datasets/procedural_scenes.hpp"
#include "datasets/query_file.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <fstream>
#include <iterator>
#include <sstream>

namespace ccd {
namespace {

using testing::cell_of;
using testing::quoted;
using testing::read_json;
using testing::run_ccdbench;

std::string built_plugin(const std::string& name) { return (std::filesystem::path(CCDBENCH_PLUGIN_DIR) / ("lib" + name + ".so")).string(); }

class Audit : public ::testing::Test {
 protected:
  void SetUp() override { ::setenv("CCDBENCH_CACHE_DIR", (dir_ / "cache").c_str(), 1); }
  void TearDown() override { ::unsetenv("CCDBENCH_CACHE_DIR"); }

  std::filesystem::path fold() { return testing::small_fold(dir_ / "fold8"); }

  /// The extremes suite's zero-motion family as query files (labelled), written by ccdbench into `folder`.
  std::filesystem::path queries(const std::string& folder) {
    const std::filesystem::path path = dir_ / folder;
    if (!std::filesystem::exists(path)) {
      EXPECT_EQ(run_ccdbench("stress --family zero-motion --write-queries " + quoted(path)).exit_code, 0);
    }
    return path;
  }

  std::pair<testing::CommandResult, nlohmann::json> with_json(const std::string& arguments) {
    return testing::run_ccdbench_with_json(arguments, dir_ / "out.json");
  }

  testing::TempDir dir_;
};

// A plugin runs isolated unless told otherwise: a crash is that query's error and the run goes on, and the spec as
// given stays as given (a baseline names it so; it used to gain ":isolate=on" under --isolate).
TEST_F(Audit, PluginsRunIsolatedByDefault) {
  const std::string crash = "full+plugin:" + built_plugin("broken_crash_on_17");
  ::setenv("ASAN_OPTIONS", "handle_segv=0", 1);
  const auto [run, summaries] =
      with_json("run --scene " + quoted(fold()) + " --max-steps 2 --strategy full," + crash + " --out " + quoted(dir_ / "o"));
  ::unsetenv("ASAN_OPTIONS");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json cell = cell_of(summaries, crash);
  EXPECT_GT(cell["errors"].get<int>(), 0);
  EXPECT_NE(cell["strategy"].get<std::string>().find(":isolate=on:timeout=10:batch=4096"), std::string::npos) << cell["strategy"];
  EXPECT_EQ(cell["provenance"].value("plugin_isolated", ""), "yes (a child process)");
}

// Queries of two files of one name in two folders, each with faults: written apart, and each fault's line names the
// file it was written to (they used to overwrite each other, and replay the wrong queries).
TEST_F(Audit, FaultsOfSameNamedFilesAreWrittenApart) {
  queries("a");
  queries("b");
  const std::filesystem::path faults = dir_ / "faults";
  const auto run = run_ccdbench("queries " + quoted(dir_ / "a") + " " + quoted(dir_ / "b") + " --faults " + quoted(faults) +
                                " --method plugin:" + built_plugin("broken_nan_toi"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::vector<std::filesystem::path> written;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(faults)) {
    if (entry.path().extension() == ".csv") written.push_back(entry.path());
  }
  EXPECT_EQ(written.size(), 4u) << "two kinds in two folders";
  std::string notes;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(faults)) {
    if (entry.path().filename() == "FAULTS.txt") notes += testing::read_text(entry.path());
  }
  std::size_t kept = 0;
  for (const std::filesystem::path& file : written) {
    EXPECT_NE(notes.find("of " + file.string() + ")"), std::string::npos) << file << " is named by no fault:\n" << notes;
    kept += datasets::read_query_file(file).queries.size();
  }
  EXPECT_EQ(kept, 2u * (14u + 7u)) << "every faulty query of both folders (14 vertex-face and 7 edge-edge each), none lost";
}

// stress shows errors apart from false negatives (a hang used to show as a miss), in text and JSON, and every JSON
// record of queries and stress carries its provenance.
TEST_F(Audit, StressCountsErrorsAndEveryJsonRecordSaysHowItWasMade) {
  const auto [stress, rows] =
      with_json("stress --family zero-motion --method plugin:" + built_plugin("broken_hang_on_3") + ":timeout=0.3,conservative");
  ASSERT_EQ(stress.exit_code, 0) << stress.output;
  EXPECT_NE(stress.output.find("errors"), std::string::npos) << stress.output;
  std::size_t errors = 0;
  for (const nlohmann::json& row : rows) {
    if (row["family"] == "(all)" && row["method"].get<std::string>().rfind("plugin:", 0) == 0) errors += row["errors"].get<std::size_t>();
    EXPECT_TRUE(row.contains("provenance")) << row.dump();
  }
  EXPECT_GT(errors, 0u) << "every third query of a child hangs";
  const auto [scored, scores] = with_json("queries " + quoted(queries("q")) + " --method conservative");
  ASSERT_EQ(scored.exit_code, 0) << scored.output;
  for (const nlohmann::json& row : scores) EXPECT_TRUE(row.contains("provenance") && row.contains("machine")) << row.dump();
}

// A TOI error nobody measured is '-' (and null in JSON), not 0: a method that reports no TOI has none checked.
TEST_F(Audit, ATimeOfImpactErrorNothingCheckedIsADash) {
  const auto [scored, scores] =
      with_json("queries " + quoted(queries("q")) + " --toi --method cubic32:eta=0,plugin:" + built_plugin("broken_silent"));
  ASSERT_EQ(scored.exit_code, 0) << scored.output;
  bool seen = false;
  for (const nlohmann::json& row : scores) {
    if (row["method"].get<std::string>().rfind("plugin:", 0) != 0 || row["file"] != "(all)") continue;
    seen = true;
    EXPECT_EQ(row["toi_checked"], 0);
    EXPECT_TRUE(row["toi_error_max"].is_null()) << row.dump();
  }
  EXPECT_TRUE(seen);
  // Its table rows (not the fault lines under the table) end with five '-': TOI late, mean, median, p99, max.
  std::istringstream lines(scored.output);
  std::size_t rows = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("plugin:", 0) != 0 || line.find("got no answer") != std::string::npos) continue;
    std::istringstream words(line);
    std::vector<std::string> tokens{std::istream_iterator<std::string>(words), std::istream_iterator<std::string>()};
    ASSERT_GE(tokens.size(), 5u);
    EXPECT_EQ(std::vector<std::string>(tokens.end() - 5, tokens.end()), std::vector<std::string>(5, "-")) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 3u);
}

// "vs full": a whole-step plugin's row against full as it runs by default, never against full+plugin (which it was
// when full was kept from an earlier run); an answers:DIR row has no time of its own: '-'.
TEST_F(Audit, SpeedUpsCompareOnlyWhatTheySay) {
  const std::string p = "plugin:" + built_plugin("my_ccd");
  const std::string scene = "run --scene " + quoted(fold()) + " --max-steps 2 --out " + quoted(dir_ / "o");
  // full is kept from here on (a run asking for its answers would compute it again)
  ASSERT_EQ(run_ccdbench(scene + " --strategy full --write-answers " + quoted(dir_ / "answers")).exit_code, 0);
  const auto [run, summaries] = with_json(scene + " --strategy full,full+" + p + "," + p);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_TRUE(cell_of(summaries, p)["speedup"].is_null()) << "compared with " << cell_of(summaries, p)["speedup_over"];
  const auto [answers, judged] = with_json("run --scene " + quoted(fold()) + " --max-steps 2 --out " + quoted(dir_ / "o2") +
                                           " --strategy full --answers " + quoted(dir_ / "answers" / "full"));
  ASSERT_EQ(answers.exit_code, 0) << answers.output;
  for (const nlohmann::json& s : judged) {
    if (s["spec"].get<std::string>().rfind("answers:", 0) == 0) {
      EXPECT_TRUE(s["speedup"].is_null()) << s.dump();
    }
  }
}

// answers:FILE:method=NAME takes a method's whole name, ':' and all, as the file holds it.
TEST_F(Audit, AnAnswerFileMethodIsNamedAsTheFileHoldsIt) {
  const std::filesystem::path answers = dir_ / "answers.csv";
  ASSERT_EQ(run_ccdbench("queries " + quoted(queries("q")) + " --method cubic64,cubic32 --write-answers " + quoted(answers)).exit_code, 0);
  const auto run = run_ccdbench("queries " + quoted(queries("q")) + " --method 'answers:" + answers.string() + ":method=cubic64:eta=1e-06'");
  EXPECT_EQ(run.exit_code, 0) << run.output;
}

// An answer path that is not a regular file is refused as FILE: REASON, exit 2; junk is refused at its first line,
// without the file being read whole.
TEST_F(Audit, AnswerPathsThatAreNotAnswerFilesAreRefused) {
  const std::string scored = "queries " + quoted(queries("q")) + " --answers ";
  std::filesystem::create_directories(dir_ / "folder");
  auto refused = [&](const std::filesystem::path& path, const std::string& reason) {
    const auto run = run_ccdbench(scored + quoted(path));
    EXPECT_EQ(run.exit_code, 2) << run.output;
    EXPECT_NE(run.output.find(path.string() + reason), std::string::npos) << run.output;
  };
  refused(dir_ / "folder", ": is a folder");
  ASSERT_EQ(::mkfifo((dir_ / "fifo").c_str(), 0600), 0);
  refused(dir_ / "fifo", ": is not a regular file");
  std::ofstream(dir_ / "junk.csv") << std::string(1 << 22, 'x');  // one 4 MB line
  refused(dir_ / "junk.csv", ":line 1: longer than");
}

// The template builds optimized unless told otherwise (CMake's default would not optimize).
TEST_F(Audit, TheTemplateBuildsReleaseUnlessToldOtherwise) {
  const std::string cmake = quoted(CCDBENCH_CMAKE);
  const auto configured = testing::run_command(cmake + " -S " + quoted(std::filesystem::path(CCDBENCH_SOURCE_DIR) / "examples" / "plugin") + " -B " +
                                               quoted(dir_ / "template") + " -DCMAKE_PREFIX_PATH=" + quoted(CCDBENCH_BUILD_DIR));
  // Configuring may fail for want of an installed package: only the build type is asked here.
  const std::string cache = testing::read_text(dir_ / "template" / "CMakeCache.txt");
  EXPECT_NE(cache.find("CMAKE_BUILD_TYPE:STRING=Release"), std::string::npos) << configured.output;
}

}  // namespace
}  // namespace ccd
