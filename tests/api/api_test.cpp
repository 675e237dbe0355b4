// The C++ API (api/ccdbench/ccdbench.hpp) as a user's program calls it: linked to libccdbench.so, in a caller's
// floating-point environment that is not IEEE's, and built against an installed ccdbench (examples/api/).

#include "ccd/config.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <xmmintrin.h>
#include <ccdbench/ccdbench.hpp>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

namespace {

using ccd::testing::quoted;
using ccd::testing::run_command;

/// MXCSR's flush-to-zero (bit 15) and denormals-are-zero (bit 6): what a program built with -Ofast runs with.
constexpr unsigned kFlushToZero = 0x8000, kDenormalsAreZero = 0x0040;

/// The extremes suite's families where flushing subnormals changes arithmetic, written by ccdbench as query files.
/// A line with its numbers masked and its blanks collapsed (what stays the same from run to run).
std::string masked(const std::string& line) {
  const std::string numbers = std::regex_replace(line, std::regex(R"([-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?)"), "#");
  std::istringstream words(numbers);
  std::string out, word;
  while (words >> word) out += (out.empty() ? "" : " ") + word;
  return out;
}

/// The lines of the ```text block that follows the ```sh block holding `command` in a docs page.
std::vector<std::string> shown_output(const std::filesystem::path& page, const std::string& command) {
  std::ifstream in(page);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::size_t k = 0;
  while (k < lines.size() && lines[k].find(command) == std::string::npos) ++k;
  while (k < lines.size() && lines[k] != "```text") ++k;
  std::vector<std::string> shown;
  for (++k; k < lines.size() && lines[k] != "```"; ++k) shown.push_back(lines[k]);
  return shown;
}

std::vector<ccdbench::QueryFile> subnormal_queries(const std::filesystem::path& folder) {
  const auto written = run_command(std::string(CCDBENCH_EXECUTABLE) + " stress --family subnormal,smallest-normal --write-queries " + quoted(folder));
  EXPECT_EQ(written.exit_code, 0) << written.output;
  std::vector<ccdbench::QueryFile> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder)) {
    if (entry.path().extension() == ".csv") files.push_back(ccdbench::read_query_file(entry.path().string()));
  }
  return files;
}

struct Answers {
  std::vector<bool> collides;
  std::vector<double> lower, upper;
  bool operator==(const Answers&) const = default;
};

Answers oracle_over(const std::vector<ccdbench::QueryFile>& files) {
  Answers answers;
  for (const ccdbench::QueryFile& file : files) {
    for (std::size_t q = 0; q < file.rounded.size(); ++q) {
      const ccdbench::ExactAnswer answer = ccdbench::exact_oracle(file.kind, file.rounded[q], 0.0);
      answers.collides.push_back(answer.collides);
      answers.lower.push_back(answer.toi_lower.value_or(-1));
      answers.upper.push_back(answer.toi_upper.value_or(-1));
    }
  }
  return answers;
}

TEST(Api, TheLibraryIsTheVersionOfItsHeader) {
  const ccdbench::Version v = ccdbench::version();
  EXPECT_EQ(v.major, CCDBENCH_API_VERSION_MAJOR);
  EXPECT_EQ(v.minor, CCDBENCH_API_VERSION_MINOR);
  EXPECT_EQ(v.patch, CCDBENCH_API_VERSION_PATCH);
}

TEST(Api, TheOracleGivesTheSameAnswersWithFlushToZeroAndGivesTheCallersEnvironmentBack) {
  ccd::testing::TempDir dir;
  const std::vector<ccdbench::QueryFile> files = subnormal_queries(dir.path() / "q");
  ASSERT_FALSE(files.empty());
  const Answers plain = oracle_over(files);
  ASSERT_GT(plain.collides.size(), 50u);
  // The labels are the reference's at δ = 0, on the same doubles (every query of this suite is exactly doubles).
  std::size_t k = 0, labelled = 0;
  for (const ccdbench::QueryFile& file : files) {
    for (std::size_t q = 0; q < file.truth.size(); ++q, ++k) {
      if (file.truth[q] < 0 || !file.exactly_double[q]) continue;
      ++labelled;
      EXPECT_EQ(plain.collides[k], file.truth[q] == 1) << file.path << " query " << q;
    }
  }
  EXPECT_GT(labelled, 50u);
  const unsigned caller = _mm_getcsr();
  _mm_setcsr(caller | kFlushToZero | kDenormalsAreZero);
  const Answers flushed = oracle_over(files);
  const unsigned after = _mm_getcsr();
  _mm_setcsr(caller);
  EXPECT_TRUE(flushed == plain) << "the oracle's answers changed with the caller's FTZ/DAZ";
  EXPECT_EQ(after & (kFlushToZero | kDenormalsAreZero), kFlushToZero | kDenormalsAreZero) << "the caller's environment was not given back";
}

TEST(Api, QueriesScoreABuiltInAndAnIsolatedPluginAsTheCommandDoes) {
  ccd::testing::TempDir dir;
  subnormal_queries(dir.path() / "q");
  const std::string plugin = "plugin:" + (std::filesystem::path(CCDBENCH_PLUGIN_DIR) / "libmy_ccd.so").string();
  // The plugin runs in a child of the ccdbench program beside the library (build/bin, as PREFIX/bin installed).
  const std::vector<ccdbench::Score> scores = ccdbench::score_queries({(dir.path() / "q").string()}, {"conservative", plugin}, 0.0, true);
  std::size_t totals = 0;
  for (const ccdbench::Score& score : scores) {
    EXPECT_EQ(score.errors, 0u) << score.method << " " << score.file;
    if (score.file != "(all)") continue;
    ++totals;
    EXPECT_EQ(score.queries, 70u) << score.method;
    if (score.method.rfind("conservative", 0) == 0) {
      EXPECT_EQ(score.false_negatives, 0u);
      EXPECT_EQ(score.toi_late, 0u);
    }
  }
  EXPECT_EQ(totals, 2u);
}

TEST(Api, TheEarliestContactIsBracketedByTheTwoDoublesAroundIt) {
  // A vertex falling onto a triangle: contact at exactly t = 0.5 (a double), and at 1/3 (not one).
  const ccdbench::Rows half = {{{0.2, 0.2, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, -1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  const ccdbench::ExactAnswer at_half = ccdbench::exact_oracle(ccdbench::PairKind::vertex_face, half, 0.0);
  ASSERT_TRUE(at_half.collides);
  EXPECT_EQ(at_half.toi_lower, 0.5);
  EXPECT_EQ(at_half.toi_upper, 0.5);
  const ccdbench::Rows third = {{{0.2, 0.2, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, -2}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  const ccdbench::ExactAnswer at_third = ccdbench::exact_oracle(ccdbench::PairKind::vertex_face, third, 0.0);
  ASSERT_TRUE(at_third.collides && at_third.toi_lower && at_third.toi_upper);
  EXPECT_EQ(std::nextafter(*at_third.toi_lower, 1.0), *at_third.toi_upper);
  EXPECT_LE(*at_third.toi_lower, 1.0 / 3.0);
  EXPECT_GE(*at_third.toi_upper, 1.0 / 3.0);
  // The same pair as rationals, and at a thickness that reaches it at t = 0.
  ccdbench::RationalRows rational;
  for (std::size_t r = 0; r < 8; ++r) {
    for (std::size_t c = 0; c < 3; ++c) rational[r][c] = c < 2 && (r == 0 || r == 4) ? "1/5" : "0";
  }
  rational[0][2] = "1";
  rational[4][2] = "-2";
  rational[2][0] = rational[6][0] = "1";
  rational[3][1] = rational[7][1] = "1";
  const ccdbench::ExactAnswer exact = ccdbench::exact_oracle(ccdbench::PairKind::vertex_face, rational, "0");
  EXPECT_EQ(exact.toi_lower, at_third.toi_lower);
  EXPECT_EQ(ccdbench::exact_oracle(ccdbench::PairKind::vertex_face, rational, "1").toi_upper, 0.0);
  EXPECT_THROW(ccdbench::exact_oracle(ccdbench::PairKind::vertex_face, rational, "one half"), std::invalid_argument);
  EXPECT_THROW(ccdbench::exact_oracle(ccdbench::PairKind::vertex_face, half, -1.0), std::invalid_argument);
}

TEST(Api, ARunOfFullAndApccdIsVerifiedAndGated) {
  ccd::testing::TempDir dir;
  ::setenv("CCDBENCH_CACHE_DIR", (dir.path() / "cache").c_str(), 1);
  const ccdbench::Scene scene = ccdbench::generate_scene("fold", {{"resolution", 8}, {"frames", 8}});
  EXPECT_EQ(scene.num_frames(), 8u);
  EXPECT_EQ(scene.frame(3).size(), scene.num_vertices());
  EXPECT_FALSE(scene.faces().empty());
  EXPECT_THROW(scene.frame(8), std::out_of_range);
  ccdbench::RunRequest request;
  request.scenes = {scene};
  request.strategies = {"full", "apccd"};
  request.toi = true;
  request.out = (dir.path() / "out").string();
  const std::vector<ccdbench::CellSummary> cells = ccdbench::run(request);
  ASSERT_EQ(cells.size(), 2u);
  std::string baseline = "[";
  for (const ccdbench::CellSummary& cell : cells) {
    ASSERT_TRUE(cell.colliding && cell.missed && cell.toi_late);
    EXPECT_GT(*cell.colliding, 0u);
    EXPECT_EQ(*cell.missed, 0u) << cell.spec;
    EXPECT_EQ(*cell.toi_late, 0u) << cell.spec;
    EXPECT_EQ(cell.steps, 7u);
    baseline += std::string(baseline.size() > 1 ? "," : "") + R"({"scene": ")" + cell.scene + R"(", "strategy": ")" + cell.spec +
                R"(", "thickness": "scene", "max_missed": 0, "colliding": )" + std::to_string(*cell.colliding) + "}";
  }
  std::ofstream(dir.path() / "baseline.json") << baseline + "]";
  const ccdbench::GateResult passed = ccdbench::check((dir.path() / "baseline.json").string(), cells);
  EXPECT_TRUE(passed.passed) << ::testing::PrintToString(passed.lines);
  std::ofstream(dir.path() / "other.json") << R"([{"scene": "fold", "strategy": "full", "thickness": "scene", "max_missed": 0}])";
  EXPECT_FALSE(ccdbench::check((dir.path() / "other.json").string(), cells).passed);
  EXPECT_THROW(ccdbench::validate_strategy("nope"), std::invalid_argument);
  ::unsetenv("CCDBENCH_CACHE_DIR");
}

TEST(Api, BadInputIsAnInvalidArgumentNamingTheFile) {
  ccd::testing::TempDir dir;
  ccd::testing::write_text(dir.path() / "vertex-face" / "bad.csv", "1,2\n");
  try {
    ccdbench::read_query_file((dir.path() / "vertex-face" / "bad.csv").string());
    FAIL() << "a malformed query file was read";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("bad.csv:"), std::string::npos) << error.what();
  }
}

// examples/api/ built against `cmake --install` output, as a user builds it, and run on the subnormal queries.
TEST(Api, TheExampleBuiltAgainstAnInstalledCcdbenchRuns) {
  ccd::testing::TempDir dir;
  const std::string cmake = quoted(CCDBENCH_CMAKE);
  const auto install = run_command(cmake + " --install " + quoted(CCDBENCH_BUILD_DIR) + " --prefix " + quoted(dir.path() / "prefix"));
  ASSERT_EQ(install.exit_code, 0) << install.output;
  for (const char* file : {"lib/libccdbench.so", "include/ccdbench/ccdbench.hpp", "bin/ccdbench"})
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "prefix" / file)) << file;
  const auto configure =
      run_command(cmake + " -S " + quoted(std::filesystem::path(CCDBENCH_SOURCE_DIR) / "examples" / "api") + " -B " + quoted(dir.path() / "build") +
                  " -DCMAKE_PREFIX_PATH=" + quoted(dir.path() / "prefix") + " -DCMAKE_CXX_COMPILER=" + quoted(CCDBENCH_TEST_CXX_COMPILER) +
                  " -DCMAKE_CXX_FLAGS=" + quoted(CCDBENCH_TEST_CXX_FLAGS) + " -DCMAKE_EXE_LINKER_FLAGS=" + quoted(CCDBENCH_TEST_EXE_LINKER_FLAGS));
  ASSERT_EQ(configure.exit_code, 0) << configure.output;
  const auto built = run_command(cmake + " --build " + quoted(dir.path() / "build"));
  ASSERT_EQ(built.exit_code, 0) << built.output;
  subnormal_queries(dir.path() / "q");
  const auto ran = run_command("CCDBENCH_CACHE_DIR=" + quoted(dir.path() / "cache") + " " + quoted(dir.path() / "build" / "api_example") + " " +
                               quoted(dir.path() / "q"));
  EXPECT_EQ(ran.exit_code, 0) << ran.output;
  EXPECT_NE(ran.output.find("0 against their label; 0 pairs missed"), std::string::npos) << ran.output;
  EXPECT_NE(ran.output.find("apccd"), std::string::npos) << ran.output;
  // What docs/cpp-api.md shows it printing, line by line, its numbers masked (as the docs walkthrough checks pages).
  const std::vector<std::string> shown = shown_output(std::filesystem::path(CCDBENCH_SOURCE_DIR) / "docs" / "cpp-api.md", "build-api/api_example q");
  ASSERT_FALSE(shown.empty()) << "docs/cpp-api.md shows no output for the example";
  std::vector<std::string> printed;
  std::istringstream lines(ran.output);
  for (std::string line; std::getline(lines, line);) printed.push_back(masked(line));
  std::size_t at = 0;
  for (const std::string& line : shown) {
    while (at < printed.size() && printed[at] != masked(line)) ++at;
    EXPECT_LT(at, printed.size()) << "docs/cpp-api.md shows a line the example does not print: " << line << "\n" << ran.output;
    if (at == printed.size()) break;
    ++at;
  }
}

}  // namespace
