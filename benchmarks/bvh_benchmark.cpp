// BVH refit and traversal on the public sample steps (rod-twist: 79,864 triangles, 2.4 million candidate pairs;
// cloth-funnel: 18,484 triangles; needs the public data). BM_SelfTraversal/<design>/<step>/<threads> compares the
// two self-traversal designs (issue 18, reports/cpu-step): per-face queries with ordered output (self_overlaps)
// and the simultaneous tree-against-tree descent with a sort (self_overlaps_tree_pairs).

#include "benchmarks/thread_counts.hpp"
#include "core/scene.hpp"
#include "datasets/data_dir.hpp"
#include "datasets/sample_step.hpp"
#include "strategies/bvh/bvh.hpp"

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <map>
#include <memory>
#include <set>
#include <string>

namespace ccd::bvh {
namespace {

const char* const kSteps[] = {"rod-twist", "cloth-funnel"};

const datasets::SampleStep* sample_step(const std::string& name) {
  static std::map<std::string, std::unique_ptr<datasets::SampleStep>> loaded;
  auto& step = loaded[name];
  if (!step) {
    const auto data = datasets::external_data_dir();
    if (!data) return nullptr;
    step = std::make_unique<datasets::SampleStep>(datasets::load_sample_step(*data / "scalable-ccd-sample" / name));
  }
  return step.get();
}

TriangleBvh fitted_tree(const datasets::SampleStep& step) {
  TriangleBvh tree;
  tree.build(step.topology, 0, step.topology.num_faces(), step.x0);
  tree.refit(step.topology, step.x0, step.x1, 0.0);
  return tree;
}

void BM_Refit(benchmark::State& state, const char* name) {
  const auto* step = sample_step(name);
  if (!step) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(0)));
  TriangleBvh tree = fitted_tree(*step);
  for (auto _ : state) tree.refit(step->topology, step->x0, step->x1, 0.0);
  state.counters["triangles"] = static_cast<double>(step->topology.num_faces());
}

template <std::vector<TrianglePair> (*traverse)(const TriangleBvh&)>
void BM_SelfTraversal(benchmark::State& state, const char* name) {
  const auto* step = sample_step(name);
  if (!step) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(0)));
  const TriangleBvh tree = fitted_tree(*step);
  // Both designs must give the same list, or the comparison means nothing (checked once per step).
  static std::set<std::string> checked;
  if (checked.insert(name).second && self_overlaps(tree) != self_overlaps_tree_pairs(tree)) {
    checked.erase(name);
    return state.SkipWithError("the designs disagree");
  }
  std::size_t candidates = 0;
  for (auto _ : state) candidates = traverse(tree).size();
  state.counters["candidate_pairs"] = static_cast<double>(candidates);
}

void BM_Build(benchmark::State& state, const char* name) {
  const auto* step = sample_step(name);
  if (!step) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  for (auto _ : state) {
    TriangleBvh tree;
    tree.build(step->topology, 0, step->topology.num_faces(), step->x0);
    benchmark::DoNotOptimize(tree);
  }
}

using benchmarks::thread_counts;

const bool registered = [] {
  for (const char* name : kSteps) {
    const std::string step(name);
    benchmark::RegisterBenchmark(("BM_SelfTraversal/per_face_ordered/" + step).c_str(), BM_SelfTraversal<self_overlaps>, name)->Apply(thread_counts);
    benchmark::RegisterBenchmark(("BM_SelfTraversal/tree_pairs_sorted/" + step).c_str(), BM_SelfTraversal<self_overlaps_tree_pairs>, name)
        ->Apply(thread_counts);
    benchmark::RegisterBenchmark(("BM_Refit/" + step).c_str(), BM_Refit, name)->Apply(thread_counts);
    benchmark::RegisterBenchmark(("BM_Build/" + step).c_str(), BM_Build, name)->Unit(benchmark::kMillisecond);
  }
  return true;
}();

}  // namespace
}  // namespace ccd::bvh

BENCHMARK_MAIN();
