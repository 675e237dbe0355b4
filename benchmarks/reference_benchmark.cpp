// Time per pair of the reference: pairs the certified filter decides, pairs the exact path decides, and the
// share the filter decides on a real step (the rod-twist sample step, when the public data is present).

#include "core/scene.hpp"
#include "datasets/data_dir.hpp"
#include "datasets/sample_step.hpp"
#include "reference/certified_filter.hpp"
#include "reference/elementary_pair.hpp"
#include "reference/step_truth.hpp"

#include <benchmark/benchmark.h>

#include <iostream>
#include <random>

namespace ccd::reference {
namespace {

struct RealPairs {
  std::vector<std::pair<PairKind, std::array<Vec3, 8>>> filter_decided;
  std::vector<std::pair<PairKind, std::array<Vec3, 8>>> filter_inconclusive;
  std::size_t total = 0;
};

/// The rod-twist sample step's own candidate pairs (its queries), split by whether the filter decides them.
const RealPairs& real_pairs() {
  static const RealPairs pairs = [] {
    RealPairs result;
    const auto data = datasets::external_data_dir();
    if (!data) return result;
    const auto step = datasets::load_sample_step(*data / "scalable-ccd-sample/rod-twist");
    for (const auto* file : {&step.vertex_face_queries, &step.edge_edge_queries}) {
      const PairKind kind = file == &step.vertex_face_queries ? PairKind::vertex_face : PairKind::edge_edge;
      for (const auto& query : file->queries) {
        ++result.total;
        const bool decided = filter_decide(kind, interval_rows(query.rounded), Interval(0.0)) != FilterVerdict::inconclusive;
        (decided ? result.filter_decided : result.filter_inconclusive).emplace_back(kind, query.rounded);
      }
    }
    return result;
  }();
  return pairs;
}

void BM_FilterDecidedPair(benchmark::State& state) {
  const auto& pairs = real_pairs().filter_decided;
  if (pairs.empty()) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& [kind, rows] = pairs[i++ % pairs.size()];
    benchmark::DoNotOptimize(decide(kind, rows, 0.0));
  }
  state.counters["filter_share"] = static_cast<double>(pairs.size()) / static_cast<double>(real_pairs().total);
}
BENCHMARK(BM_FilterDecidedPair)->Unit(benchmark::kMicrosecond);

void BM_ExactDecidedPair(benchmark::State& state) {
  // Pairs the filter leaves open, or when it decides everything, the same pairs forced down the exact path.
  const auto& open = real_pairs().filter_inconclusive;
  const auto& pairs = open.empty() ? real_pairs().filter_decided : open;
  if (pairs.empty()) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& [kind, rows] = pairs[i++ % pairs.size()];
    benchmark::DoNotOptimize(decide(kind, rows, 0.0, {false, false, 0}));
  }
  state.counters["inconclusive_share"] = static_cast<double>(open.size()) / static_cast<double>(real_pairs().total);
}
BENCHMARK(BM_ExactDecidedPair)->Unit(benchmark::kMicrosecond);

/// Random pairs whose face lies 2 above its vertex's unit box: the far pairs most of a step's candidates are.
void BM_FilterFarPair(benchmark::State& state) {
  std::mt19937_64 random(42);
  std::uniform_real_distribution<double> coordinate(0.0, 1.0);
  std::vector<std::array<Vec3, 8>> pairs(1024);
  for (auto& rows : pairs) {
    for (int r = 0; r < 8; ++r) {
      const double lift = r % 4 == 0 ? 0.0 : 2.0;  // rows 0 and 4 are the vertex, the others the face
      rows[r] = Vec3(coordinate(random), coordinate(random), coordinate(random) + lift);
    }
  }
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(filter_decide(PairKind::vertex_face, interval_rows(pairs[i++ % 1024]), Interval(0.0)));
}
BENCHMARK(BM_FilterFarPair)->Unit(benchmark::kMicrosecond);

/// Whole-step truth of the rod-twist sample step: the share of its pairs the filter decides, and the time.
void BM_StepTruthRodTwist(benchmark::State& state) {
  const auto data = datasets::external_data_dir();
  if (!data) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  const auto step = datasets::load_sample_step(*data / "scalable-ccd-sample/rod-twist");
  const Scene scene({{"rod", ObjectKind::deformable, true, step.topology.num_vertices(), step.topology.faces()}}, {}, 0.0);
  TruthStatistics statistics;
  for (auto _ : state) statistics = compute_step_truth(scene, step.x0, step.x1, {0.0, false, {}}).statistics;
  const double pairs = static_cast<double>(statistics.vertex_face_pairs + statistics.edge_edge_pairs);
  state.counters["pairs"] = pairs;
  state.counters["filter_share"] = static_cast<double>(statistics.decided_by_filter) / pairs;
  state.counters["exact_pairs"] = static_cast<double>(statistics.decided_exactly);
}
BENCHMARK(BM_StepTruthRodTwist)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace ccd::reference

BENCHMARK_MAIN();
