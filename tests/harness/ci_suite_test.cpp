// The `ci` suite is what the CI gate holds strategies to: it must be able to catch a miss of every kind.

#include "harness/run.hpp"
#include "harness/run/tables.hpp"
#include "reference/step_truth.hpp"
#include "strategies/registry.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace ccd::harness {
namespace {

double extra(const strategies::StepResult& result, const std::string& name) {
  for (const auto& [key, value] : result.counters.extra) {
    if (key == name) return value;
  }
  return -1;
}

// At the scenes' δ and at δ = 0: every scene collides (a gated cell without colliding pairs gates nothing), and
// the suite has self contact, contact between objects, and contacts that apccd meets inside its sessions.
TEST(CiSuite, EveryCellCollidesWithContactsOfEveryKindAtBothThicknesses) {
  testing::TempDir cache;
  ::setenv("CCDBENCH_CACHE_DIR", cache.path().c_str(), 1);
  for (const bool zero : {false, true}) {
    std::size_t self = 0, across = 0, inside_sessions = 0, face_sphere = 0, face_box = 0;
    for (const SceneSource& source : suite_scenes("ci")) {
      datasets::SceneSequence sequence = source.load();
      if (zero) sequence.set_thickness(0.0);
      const Scene& scene = sequence.scene();
      SCOPED_TRACE(source.label + ", δ = " + std::to_string(scene.thickness()));
      auto apccd = strategies::make_strategy("apccd");
      std::vector<Vec3> x0 = sequence.frame(0);
      apccd->init(scene, x0);
      std::size_t colliding = 0;
      for (std::size_t k = 0; k < sequence.num_steps(); ++k) {
        const std::vector<Vec3> x1 = sequence.frame(k + 1);
        const auto truth = reference::compute_step_truth(scene, x0, x1, {scene.thickness(), false, {}}).collisions;
        for (const auto& c : truth.vertex_face()) (scene.object_of_vertex(c.pair.v) == scene.object_of_face(c.pair.f) ? self : across) += 1;
        for (const auto& c : truth.edge_edge()) (scene.object_of_vertex(c.pair.a.v0) == scene.object_of_vertex(c.pair.b.v0) ? self : across) += 1;
        for (const auto& c : truth.face_shape()) (scene.object(c.pair.shape).shape->kind == ShapeKind::sphere ? face_sphere : face_box) += 1;
        const strategies::StepResult result = apccd->step({&scene, k, x0, x1}, false);
        if (extra(result, "session_start") == 0.0) inside_sessions += truth.size();
        colliding += truth.size();
        x0 = x1;
      }
      EXPECT_GT(colliding, 0u);
    }
    SCOPED_TRACE(zero ? "δ = 0" : "the scenes' δ");
    EXPECT_GT(self, 0u);
    EXPECT_GT(across, 0u);
    EXPECT_GT(inside_sessions, 0u);
    EXPECT_GT(face_sphere, 0u) << "the suite must gate face-sphere pairs";
    EXPECT_GT(face_box, 0u) << "the suite must gate face-box pairs";
  }
  ::unsetenv("CCDBENCH_CACHE_DIR");
}

// A summary carries each strategy counter's mean and max over its steps (apccd's session starts, pending pairs,
// ...) and the mean ms per step beside the median: they must be the steps' own values.
TEST(RunSummary, StrategyCountersHaveTheirMeanAndMaxOverTheSteps) {
  testing::TempDir dir;
  ::setenv("CCDBENCH_CACHE_DIR", dir.path().c_str(), 1);
  RunOptions options;
  options.scenes = {suite_scenes("ci").back()};
  options.strategies = {strategies::parse_strategy_spec("apccd")};
  options.verify = false;
  options.out = dir.path() / "results";
  const nlohmann::json summaries = summaries_json(run_benchmark(options).cells);
  ::unsetenv("CCDBENCH_CACHE_DIR");
  ASSERT_EQ(summaries.size(), 1u);
  const nlohmann::json& summary = summaries[0];
  std::vector<nlohmann::json> steps;
  std::ifstream in(options.out / "results.jsonl");
  for (std::string line; std::getline(in, line);) {
    const nlohmann::json record = nlohmann::json::parse(line);
    if (record.value("record", "") == "step") steps.push_back(record);
  }
  ASSERT_EQ(steps.size(), summary["steps"].get<std::size_t>());
  for (const char* name : {"session_start", "pending_pairs", "nf"}) {
    double sum = 0, most = 0;
    for (const nlohmann::json& step : steps) {
      sum += step[name].get<double>();
      most = std::max(most, step[name].get<double>());
    }
    EXPECT_DOUBLE_EQ(summary["counters"][name]["mean"].get<double>(), sum / static_cast<double>(steps.size())) << name;
    EXPECT_EQ(summary["counters"][name]["max"].get<double>(), most) << name;
  }
  EXPECT_GT(summary["counters"]["pending_pairs"]["max"].get<double>(), 0.0);
  double ms = 0;
  for (const nlohmann::json& step : steps) ms += step["ms"].get<double>();
  EXPECT_DOUBLE_EQ(summary["ms_per_step_mean"].get<double>(), ms / static_cast<double>(steps.size()));
  // Each stage's mean per step (steps without it add 0): within a step, the stages take part of its time.
  double stages = 0;
  for (const auto& [stage, value] : summary["stage_ms_mean"].items()) {
    double sum = 0;
    for (const nlohmann::json& step : steps) sum += step["stages"].value(stage, 0.0);
    EXPECT_NEAR(value.get<double>(), sum / static_cast<double>(steps.size()), 1e-9 * sum) << stage;
    stages += value.get<double>();
  }
  EXPECT_GT(stages, 0.0);
  EXPECT_LE(stages, summary["ms_per_step_mean"].get<double>());
  // The time no stage names: each step's ms less its own stages, averaged (one pass here, so the step records hold
  // every timed step).
  double unattributed = 0;
  for (const nlohmann::json& step : steps) {
    double named = 0;
    for (const auto& [stage, value] : step["stages"].items()) named += value.get<double>();
    unattributed += step["ms"].get<double>() - named;
  }
  EXPECT_NEAR(summary["unattributed_ms_mean"].get<double>(), unattributed / static_cast<double>(steps.size()), 1e-9 * ms);
}

// A cell's start (making the strategy, its init on the first frame: apccd builds its hierarchies there) is timed
// apart from its steps, in the summary that --json and results.jsonl both write.
TEST(RunSummary, ACellsStartIsTimedApartFromItsSteps) {
  testing::TempDir dir;
  ::setenv("CCDBENCH_CACHE_DIR", dir.path().c_str(), 1);
  RunOptions options;
  options.scenes = {suite_scenes("ci").front()};
  options.strategies = {strategies::parse_strategy_spec("apccd")};
  options.verify = false;
  options.repeats = 2;
  options.out = dir.path() / "results";
  const nlohmann::json summaries = summaries_json(run_benchmark(options).cells);
  ::unsetenv("CCDBENCH_CACHE_DIR");
  ASSERT_EQ(summaries.size(), 1u);
  ASSERT_TRUE(summaries[0].contains("setup_ms") && summaries[0]["setup_ms"].is_number()) << summaries[0].dump();
  EXPECT_GT(summaries[0]["setup_ms"].get<double>(), 0.0);
  std::ifstream in(options.out / "results.jsonl");
  std::size_t found = 0;
  for (std::string line; std::getline(in, line);) {
    const nlohmann::json record = nlohmann::json::parse(line);
    if (record.value("record", "") != "summary") continue;
    EXPECT_EQ(record["setup_ms"], summaries[0]["setup_ms"]);
    ++found;
  }
  EXPECT_EQ(found, 1u);
}

}  // namespace
}  // namespace ccd::harness
