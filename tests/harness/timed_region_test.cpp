// The harness times the strategy's work alone (issue 36): every harness-side pass (verification, the answers'
// digest, miss, fault and answer files, query scoring) announces itself, and none may find itself inside a
// strategy's timed region. Moving one there on purpose (e.g. the digest into run_cell's step call) fails this test.

#include "harness/timed_region.hpp"
#include "datasets/query_file.hpp"
#include "harness/queries/scoring.hpp"
#include "harness/run.hpp"
#include "harness/run/tables.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>

namespace ccd::harness {
namespace {

std::string listed(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

TEST(TimedRegion, NoHarnessPassRunsInsideAStrategysTime) {
  testing::TempDir dir;
  ::setenv("CCDBENCH_CACHE_DIR", dir.path().c_str(), 1);
  clear_harness_passes_in_timed_region();
  RunOptions options;
  options.scenes = {suite_scenes("ci")[1]};  // fold-r8-f24
  options.thicknesses = {0.0};
  // cubic32 misses on this scene at δ = 0, so that the audit pass and the miss records run too.
  options.strategies = {strategies::parse_strategy_spec("full"), strategies::parse_strategy_spec("full+cubic32")};
  options.toi = true;
  options.out = dir.path() / "results";
  options.misses = dir.path() / "misses";
  options.write_answers = dir.path() / "answers";
  const nlohmann::json summaries = summaries_json(run_benchmark(options).cells);
  ::unsetenv("CCDBENCH_CACHE_DIR");
  ASSERT_EQ(summaries.size(), 2u);
  EXPECT_GT(summaries[1]["missed"].get<std::size_t>(), 0u) << "full+cubic32 no longer misses here: the miss records go untested";
  EXPECT_GT(harness_passes_announced(), 0u);
  EXPECT_TRUE(harness_passes_in_timed_region().empty()) << "inside a timed step: " << listed(harness_passes_in_timed_region());
}

TEST(TimedRegion, QueryScoringIsOutsideTheTimedAnswers) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  clear_harness_passes_in_timed_region();
  const datasets::QueryFile file = datasets::read_query_file(data / "sample-queries/unit-tests/vertex-face/data_0_0.csv");
  QueryScoringRequest request;
  request.methods = {"cubic64", "conservative"};
  request.toi = true;
  request.repeats = 2;
  const std::vector<QueryScore> scores = score_query_file(file, request);
  ASSERT_EQ(scores.size(), 2u);
  EXPECT_GT(harness_passes_announced(), 0u);
  EXPECT_TRUE(harness_passes_in_timed_region().empty()) << "inside the timed answers: " << listed(harness_passes_in_timed_region());
}

}  // namespace
}  // namespace ccd::harness
