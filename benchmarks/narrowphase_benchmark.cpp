// Each narrow phase's VF and EE calls on realistic inputs: the rod-twist sample step's candidate queries (mostly
// colliding), and the candidate pairs a broad phase hands over on a whole step (overlapping swept boxes of the
// cloth-funnel sample step, mostly far apart). Needs the public data (CCDBENCH_DATA_DIR).

#include "core/step.hpp"
#include "datasets/data_dir.hpp"
#include "datasets/query_file.hpp"
#include "datasets/sample_step.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "strategies/separation_filter.hpp"

#include <benchmark/benchmark.h>

#include <map>

namespace ccd::narrowphase {
namespace {

using Pairs = std::vector<PairRows>;

struct Inputs {
  std::map<std::string, Pairs> sets;  // "<set>/<vf|ee>"
};

/// Candidate pairs of a step by brute force over overlapping swept boxes (a small step, so brute force is fine).
void broad_phase_pairs(const datasets::SampleStep& step, Pairs& vf, Pairs& ee, std::size_t limit) {
  const MeshTopology& topology = step.topology;
  auto box_of = [&](std::initializer_list<VertexId> vertices) {
    Box3 box;
    for (VertexId v : vertices) {
      box.extend(step.x0[v]);
      box.extend(step.x1[v]);
    }
    return box;
  };
  std::vector<Box3> face_boxes, edge_boxes;
  for (FaceId f = 0; f < topology.num_faces(); ++f) {
    const Face& face = topology.face(f);
    face_boxes.push_back(box_of({face[0], face[1], face[2]}));
  }
  for (EdgeId e = 0; e < topology.num_edges(); ++e) edge_boxes.push_back(box_of({topology.edge(e).v0, topology.edge(e).v1}));
  for (VertexId v = 0; v < topology.num_vertices() && vf.size() < limit; v += 7) {
    const Box3 box = box_of({v});
    for (FaceId f = 0; f < topology.num_faces() && vf.size() < limit; ++f) {
      const Face& face = topology.face(f);
      if (v == face[0] || v == face[1] || v == face[2] || !box.intersects(face_boxes[f])) continue;
      vf.push_back(pair_rows(topology, step.x0, step.x1, VertexFacePair{v, f}));
    }
  }
  for (EdgeId a = 0; a < topology.num_edges() && ee.size() < limit; a += 7) {
    const Edge ea = topology.edge(a);
    for (EdgeId b = a + 1; b < topology.num_edges() && ee.size() < limit; ++b) {
      const Edge eb = topology.edge(b);
      if (shares_vertex(ea, eb) || !edge_boxes[a].intersects(edge_boxes[b])) continue;
      ee.push_back(pair_rows(topology, step.x0, step.x1, EdgeEdgePair{ea, eb}));
    }
  }
}

const Inputs& inputs() {
  static const Inputs loaded = [] {
    Inputs result;
    const auto data = datasets::external_data_dir();
    if (!data) return result;
    const auto rod = datasets::load_sample_step(*data / "scalable-ccd-sample/rod-twist");
    for (const auto& query : rod.vertex_face_queries.queries) result.sets["queries/vf"].push_back(query.rounded);
    for (const auto& query : rod.edge_edge_queries.queries) result.sets["queries/ee"].push_back(query.rounded);
    const auto cloth = datasets::load_sample_step(*data / "scalable-ccd-sample/cloth-funnel");
    broad_phase_pairs(cloth, result.sets["candidates/vf"], result.sets["candidates/ee"], 20000);
    return result;
  }();
  return loaded;
}

void BM_NarrowPhase(benchmark::State& state, const std::string& spec, const std::string& set) {
  const auto it = inputs().sets.find(set);
  if (it == inputs().sets.end() || it->second.empty()) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  const auto variant = make_narrow_phase_from_spec(spec);
  const bool vertex_face = set.ends_with("/vf");
  const Pairs& pairs = it->second;
  std::size_t i = 0, collisions = 0;
  for (auto _ : state) {
    const PairRows& rows = pairs[i++ % pairs.size()];
    const NarrowPhaseResult result = vertex_face ? variant->vertex_face(rows, 0.0) : variant->edge_edge(rows, 0.0);
    collisions += result.collides ? 1 : 0;
    benchmark::DoNotOptimize(result);
  }
  state.counters["pairs"] = static_cast<double>(pairs.size());
  state.counters["collide_share"] = static_cast<double>(collisions) / static_cast<double>(std::max<std::size_t>(1, i));
}

/// apccd's distance heuristic (strategies/separation_filter.hpp) on the same pairs: what it costs per pair beside
/// the narrow phases it runs in front of (it pays only where it is cheaper than the test it spares).
void BM_SeparationFilter(benchmark::State& state, const std::string& set) {
  const auto it = inputs().sets.find(set);
  if (it == inputs().sets.end() || it->second.empty()) return state.SkipWithError("no public data (CCDBENCH_DATA_DIR)");
  const bool vertex_face = set.ends_with("/vf");
  const Pairs& pairs = it->second;
  std::size_t i = 0, apart = 0;
  for (auto _ : state) {
    const bool proven = strategies::provably_apart(pairs[i++ % pairs.size()], vertex_face, 0.0);
    apart += proven ? 1 : 0;
    benchmark::DoNotOptimize(proven);
  }
  state.counters["pairs"] = static_cast<double>(pairs.size());
  state.counters["apart_share"] = static_cast<double>(apart) / static_cast<double>(std::max<std::size_t>(1, i));
}

const bool registered = [] {
  for (const char* set : {"queries/vf", "queries/ee", "candidates/vf", "candidates/ee"}) {
    benchmark::RegisterBenchmark((std::string("separation-filter/") + set).c_str(), BM_SeparationFilter, std::string(set))
        ->Unit(benchmark::kNanosecond);
  }
  for (const char* spec : {"cubic32", "cubic64", "conservative", "advancement"}) {
    for (const char* set : {"queries/vf", "queries/ee", "candidates/vf", "candidates/ee"}) {
      benchmark::RegisterBenchmark((std::string(spec) + "/" + set).c_str(), BM_NarrowPhase, std::string(spec), std::string(set))
          ->Unit(benchmark::kNanosecond);
    }
  }
  return true;
}();

}  // namespace
}  // namespace ccd::narrowphase

BENCHMARK_MAIN();
