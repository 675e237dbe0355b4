// BVH refit and traversal on the rod-twist sample step (80k triangles; needs the public data).

#include "core/scene.hpp"
#include "datasets/data_dir.hpp"
#include "datasets/sample_step.hpp"
#include "strategies/bvh/bvh.hpp"

#include <benchmark/benchmark.h>

namespace ccd::bvh {
namespace {

const datasets::SampleStep* rod_twist() {
  static const std::unique_ptr<datasets::SampleStep> step = []() -> std::unique_ptr<datasets::SampleStep> {
    const auto data = datasets::external_data_dir();
    if (!data) return nullptr;
    return std::make_unique<datasets::SampleStep>(datasets::load_sample_step(*data / "scalable-ccd-sample/rod-twist"));
  }();
  return step.get();
}

void BM_Refit(benchmark::State& state) {
  const auto* step = rod_twist();
  if (!step) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  TriangleBvh tree;
  tree.build(step->topology, 0, step->topology.num_faces(), step->x0);
  for (auto _ : state) tree.refit(step->topology, step->x0, step->x1, 0.0);
  state.counters["triangles"] = static_cast<double>(step->topology.num_faces());
}
BENCHMARK(BM_Refit)->Unit(benchmark::kMillisecond);

void BM_SelfTraversal(benchmark::State& state) {
  const auto* step = rod_twist();
  if (!step) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  TriangleBvh tree;
  tree.build(step->topology, 0, step->topology.num_faces(), step->x0);
  tree.refit(step->topology, step->x0, step->x1, 0.0);
  std::size_t candidates = 0;
  for (auto _ : state) candidates = self_overlaps(tree).size();
  state.counters["candidate_pairs"] = static_cast<double>(candidates);
}
BENCHMARK(BM_SelfTraversal)->Unit(benchmark::kMillisecond);

void BM_Build(benchmark::State& state) {
  const auto* step = rod_twist();
  if (!step) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  for (auto _ : state) {
    TriangleBvh tree;
    tree.build(step->topology, 0, step->topology.num_faces(), step->x0);
    benchmark::DoNotOptimize(tree);
  }
}
BENCHMARK(BM_Build)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ccd::bvh

BENCHMARK_MAIN();
