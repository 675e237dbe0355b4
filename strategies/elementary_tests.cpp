#include "strategies/elementary_tests.hpp"

#include "strategies/separation_filter.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace ccd::strategies {
namespace {

struct Local {
  CollisionSet collisions;
  std::size_t tests = 0;
  std::size_t filtered = 0;
  TestedPairs tested;
};

bool corner_of(VertexId v, const Face& f) { return v == f[0] || v == f[1] || v == f[2]; }

}  // namespace

ElementaryOutcome test_candidates(const MeshTopology& topology, std::span<const AssignmentMask> masks,
                                  std::span<const bvh::TrianglePair> candidates, const StepView& step,
                                  const narrowphase::NarrowPhase& narrow_phase, double thickness, bool audit,
                                  bool separation_filter) {
  const auto& x0 = step.x0;
  const auto& x1 = step.x1;
  // Swept vertex boxes widened by δ/2: a primitive pair whose boxes are apart cannot come within δ, so the cheap
  // box test spares the narrow phase most pairs of a candidate triangle pair (they are counted as culled).
  std::vector<Box3> vertex_boxes(x0.size());
  tbb::parallel_for(std::size_t{0}, x0.size(), [&](std::size_t v) {
    Box3 box(x0[v]);
    box.extend(x1[v]);
    vertex_boxes[v] = bvh::widened(box, thickness / 2);
  });
  auto box_of = [&](std::initializer_list<VertexId> vertices) {
    Box3 box;
    for (VertexId v : vertices) box.extend(vertex_boxes[v]);
    return box;
  };
  tbb::enumerable_thread_specific<Local> locals;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 64), [&](const auto& range) {
    Local& local = locals.local();
    auto vertex_against_face = [&](VertexId v, FaceId f) {
      const Face& face = topology.face(f);
      if (corner_of(v, face) || !vertex_boxes[v].intersects(box_of({face[0], face[1], face[2]}))) return;
      const VertexFacePair pair{v, f};
      const narrowphase::PairRows rows = pair_rows(topology, x0, x1, pair);
      if (separation_filter && provably_apart(rows, true, thickness)) {
        ++local.filtered;
        return;
      }
      ++local.tests;
      if (audit) local.tested.vertex_face.push_back(pair);
      const narrowphase::NarrowPhaseResult r = narrow_phase.vertex_face(rows, thickness);
      if (r.collides) local.collisions.add(pair, r.toi);
    };
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const auto [a, b] = candidates[i];
      for (const auto& [owner, other] : {std::pair{a, b}, std::pair{b, a}}) {
        for (int k = 0; k < 3; ++k) {
          if (masks[owner] & owns_vertex_bit(k)) vertex_against_face(topology.face(owner)[k], other);
        }
      }
      for (int i_edge = 0; i_edge < 3; ++i_edge) {
        if (!(masks[a] & owns_edge_bit(i_edge))) continue;
        const Edge ea = topology.edge(topology.face_edges(a)[i_edge]);
        for (int j_edge = 0; j_edge < 3; ++j_edge) {
          if (!(masks[b] & owns_edge_bit(j_edge))) continue;
          const Edge eb = topology.edge(topology.face_edges(b)[j_edge]);
          if (shares_vertex(ea, eb)) continue;
          if (!box_of({ea.v0, ea.v1}).intersects(box_of({eb.v0, eb.v1}))) continue;
          const EdgeEdgePair pair = make_edge_edge_pair(ea, eb);
          const narrowphase::PairRows rows = pair_rows(topology, x0, x1, pair);
          if (separation_filter && provably_apart(rows, false, thickness)) {
            ++local.filtered;
            continue;
          }
          ++local.tests;
          if (audit) local.tested.edge_edge.push_back(pair);
          const narrowphase::NarrowPhaseResult r = narrow_phase.edge_edge(rows, thickness);
          if (r.collides) local.collisions.add(pair, r.toi);
        }
      }
    }
  });
  ElementaryOutcome outcome;
  if (audit) outcome.tested.emplace();
  for (Local& local : locals) {
    outcome.collisions.append(local.collisions);
    outcome.tests += local.tests;
    outcome.filtered += local.filtered;
    if (audit) {
      outcome.tested->vertex_face.insert(outcome.tested->vertex_face.end(), local.tested.vertex_face.begin(), local.tested.vertex_face.end());
      outcome.tested->edge_edge.insert(outcome.tested->edge_edge.end(), local.tested.edge_edge.begin(), local.tested.edge_edge.end());
    }
  }
  outcome.collisions.normalize();
  if (audit) {
    tbb::parallel_sort(outcome.tested->vertex_face.begin(), outcome.tested->vertex_face.end());
    tbb::parallel_sort(outcome.tested->edge_edge.begin(), outcome.tested->edge_edge.end());
  }
  return outcome;
}

void run_narrow_phase(StepResult& result, const MeshTopology& topology, std::span<const AssignmentMask> masks,
                      std::span<const bvh::TrianglePair> candidates, const StepView& step,
                      const narrowphase::NarrowPhase& narrow_phase, double thickness, bool audit, bool separation_filter) {
  ElementaryOutcome outcome;
  {
    ScopedStageTimer timer(result.stages, "narrow phase");
    outcome = test_candidates(topology, masks, candidates, step, narrow_phase, thickness, audit, separation_filter);
  }
  if (separation_filter) result.counters.extra.emplace_back("distance_filtered", static_cast<double>(outcome.filtered));
  result.collisions = std::move(outcome.collisions);
  result.tested = std::move(outcome.tested);
  result.counters.candidate_triangle_pairs = candidates.size();
  result.counters.elementary_tests = outcome.tests;
}

void append_all_elementary_pairs(const MeshTopology& topology, FaceId a, FaceId b, TestedPairs& out) {
  for (const auto& [from, to] : {std::pair{a, b}, std::pair{b, a}}) {
    for (VertexId v : topology.face(from)) {
      if (!corner_of(v, topology.face(to))) out.vertex_face.push_back({v, to});
    }
  }
  for (EdgeId i : topology.face_edges(a)) {
    const Edge ea = topology.edge(i);
    for (EdgeId j : topology.face_edges(b)) {
      const Edge eb = topology.edge(j);
      if (shares_vertex(ea, eb)) continue;
      out.edge_edge.push_back(make_edge_edge_pair(ea, eb));
    }
  }
}

}  // namespace ccd::strategies
