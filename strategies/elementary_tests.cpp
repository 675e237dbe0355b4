#include "strategies/elementary_tests.hpp"

#include "strategies/separation_filter.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <type_traits>

namespace ccd::strategies {
namespace {

struct Local {
  CollisionSet collisions;
  std::size_t tests = 0;
  std::size_t filtered = 0;
  TestedPairs tested;
  /// The pairs the separation filter kept, for the narrow phase's own pass.
  TestedPairs kept;
  /// Faults of the narrow phase, each with its pair's order key (VF before EE, then by pair), and how many.
  std::vector<std::pair<std::array<std::uint32_t, 5>, Fault>> faults;
  std::size_t fault_count = 0;
};

/// A pair's place among a step's faults: vertex-face pairs first, then edge-edge pairs, each in pair order.
std::array<std::uint32_t, 5> order_key(const VertexFacePair& p) { return {0, p.v, p.f, 0, 0}; }
std::array<std::uint32_t, 5> order_key(const EdgeEdgePair& p) { return {1, p.a.v0, p.a.v1, p.b.v0, p.b.v1}; }

bool corner_of(VertexId v, const Face& f) { return v == f[0] || v == f[1] || v == f[2]; }

/// The VF or the EE list of `pairs`.
template <bool vertex_face>
auto& list_of(TestedPairs& pairs) {
  if constexpr (vertex_face) {
    return pairs.vertex_face;
  } else {
    return pairs.edge_edge;
  }
}

/// Each primitive's swept box over the step, widened by δ/2: a primitive pair whose boxes are apart cannot come
/// within δ. A face's box is the union of its corners' boxes and an edge's of its ends' (min and max: exact), each
/// formed once per step instead of once per candidate that holds it (a face is in about nine candidates).
struct PrimitiveBoxes {
  std::vector<Box3> vertex, edge, face;
};

/// Calls vertex_face(pair) and edge_edge(pair) for each elementary pair of candidate (a, b) that the masks give and
/// whose primitives' boxes overlap: the cheap box test spares the narrow phase most pairs of a candidate triangle
/// pair (they are counted as culled). Every primitive's box lies in its face's box, so a candidate whose face boxes
/// are apart has none.
template <class VertexFace, class EdgeEdge>
void for_each_elementary_pair(const MeshTopology& topology, std::span<const AssignmentMask> masks, const PrimitiveBoxes& boxes, FaceId a, FaceId b,
                              VertexFace&& vertex_face, EdgeEdge&& edge_edge) {
  if (!boxes_overlap(boxes.face[a], boxes.face[b])) return;
  for (const auto& [owner, other] : {std::pair{a, b}, std::pair{b, a}}) {
    const Face& face = topology.face(other);
    const Face& own = topology.face(owner);
    for (int k = 0; k < 3; ++k) {
      if (!(masks[owner] & owns_vertex_bit(k))) continue;
      const VertexId v = own[k];
      if (corner_of(v, face) || !boxes_overlap(boxes.vertex[v], boxes.face[other])) continue;
      vertex_face(VertexFacePair{v, other});
    }
  }
  for (int i_edge = 0; i_edge < 3; ++i_edge) {
    if (!(masks[a] & owns_edge_bit(i_edge))) continue;
    const EdgeId ia = topology.face_edges(a)[i_edge];
    const Edge ea = topology.edge(ia);
    for (int j_edge = 0; j_edge < 3; ++j_edge) {
      if (!(masks[b] & owns_edge_bit(j_edge))) continue;
      const EdgeId ib = topology.face_edges(b)[j_edge];
      const Edge eb = topology.edge(ib);
      if (shares_vertex(ea, eb) || !boxes_overlap(boxes.edge[ia], boxes.edge[ib])) continue;
      edge_edge(make_edge_edge_pair(ea, eb));
    }
  }
}

/// The swept boxes of every vertex (widened by δ/2, so that two boxes apart means the primitives stay farther than δ),
/// edge and face of a step, in parallel.
PrimitiveBoxes primitive_boxes(const MeshTopology& topology, std::span<const Vec3> x0, std::span<const Vec3> x1, double thickness) {
  PrimitiveBoxes boxes;
  boxes.vertex.resize(x0.size());
  tbb::parallel_for(std::size_t{0}, x0.size(), [&](std::size_t v) {
    Box3 box(x0[v]);
    box.extend(x1[v]);
    boxes.vertex[v] = bvh::widened(box, thickness / 2);
  });
  boxes.edge.resize(topology.num_edges());
  tbb::parallel_for(std::size_t{0}, topology.num_edges(), [&](std::size_t e) {
    const Edge edge = topology.edge(static_cast<EdgeId>(e));
    boxes.edge[e] = boxes.vertex[edge.v0].merged(boxes.vertex[edge.v1]);
  });
  boxes.face.resize(topology.num_faces());
  tbb::parallel_for(std::size_t{0}, topology.num_faces(), [&](std::size_t f) {
    const Face& face = topology.face(static_cast<FaceId>(f));
    boxes.face[f] = boxes.vertex[face[0]].merged(boxes.vertex[face[1]]).merged(boxes.vertex[face[2]]);
  });
  return boxes;
}

/// The narrow phase's answer `r` on one elementary pair (VertexFacePair or EdgeEdgePair), recorded in a thread's list.
template <typename Pair>
void record_answer(Local& local, const Pair& pair, const narrowphase::PairRows& rows, const narrowphase::NarrowPhaseResult& r, bool audit) {
  constexpr bool vertex_face = std::is_same_v<Pair, VertexFacePair>;
  ++local.tests;
  if (audit) list_of<vertex_face>(local.tested).push_back(pair);
  if (r.collides) local.collisions.add(pair, r.toi);
  if (!r.fault.empty()) {
    ++local.fault_count;
    local.faults.push_back({order_key(pair), Fault{r.fault, rows, vertex_face}});
    // A thread keeps its first faults in pair order only: the step keeps kKeptFaults of every thread's.
    if (local.faults.size() > 4 * kKeptFaults) {
      std::sort(local.faults.begin(), local.faults.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      local.faults.resize(kKeptFaults);
    }
  }
}

/// `pairs` asked of `narrow_phase` in batches of its preferred size, in order, from this thread; answers recorded.
template <typename Pair>
void ask_in_batches(const narrowphase::NarrowPhase& narrow_phase, const MeshTopology& topology, const StepView& step, double thickness,
                    const std::vector<Pair>& pairs, Local& local, bool audit) {
  constexpr bool vertex_face = std::is_same_v<Pair, VertexFacePair>;
  const std::size_t batch = narrow_phase.preferred_batch();
  std::vector<narrowphase::PairRows> rows;
  std::vector<narrowphase::NarrowPhase::BatchPair> asked;
  std::vector<narrowphase::NarrowPhaseResult> results;
  for (std::size_t first = 0; first < pairs.size(); first += batch) {
    const std::size_t count = std::min(batch, pairs.size() - first);
    rows.resize(count);
    asked.resize(count);
    results.assign(count, {});
    for (std::size_t i = 0; i < count; ++i) {
      rows[i] = pair_rows(topology, step.x0, step.x1, pairs[first + i]);
      asked[i] = {&rows[i], vertex_face, thickness};
    }
    narrow_phase.answer_batch(asked, results);
    for (std::size_t i = 0; i < count; ++i) record_answer(local, pairs[first + i], rows[i], results[i], audit);
  }
}

/// Every thread's answers as the step's outcome: the collision set in order, counts added up, the first faults in pair
/// order whatever thread met them (the same for any thread count), the tested pairs sorted; the thread lists freed.
ElementaryOutcome assemble_outcome(tbb::enumerable_thread_specific<Local>& locals, bool audit) {
  ElementaryOutcome outcome;
  if (audit) outcome.tested.emplace();
  std::vector<std::pair<std::array<std::uint32_t, 5>, Fault>> faults;
  std::vector<CollisionSet*> sets;
  for (Local& local : locals) sets.push_back(&local.collisions);
  outcome.collisions = normalize_in_parallel(std::move(sets));
  for (Local& local : locals) {
    outcome.tests += local.tests;
    outcome.filtered += local.filtered;
    outcome.fault_count += local.fault_count;
    for (auto& fault : local.faults) faults.push_back(std::move(fault));
    if (audit) {
      outcome.tested->vertex_face.insert(outcome.tested->vertex_face.end(), local.tested.vertex_face.begin(), local.tested.vertex_face.end());
      outcome.tested->edge_edge.insert(outcome.tested->edge_edge.end(), local.tested.edge_edge.begin(), local.tested.edge_edge.end());
    }
  }
  locals.clear();
  // The first faults in pair order, whatever thread met them: the same for any thread count.
  std::sort(faults.begin(), faults.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (std::size_t i = 0; i < std::min(faults.size(), kKeptFaults); ++i) outcome.faults.push_back(std::move(faults[i].second));
  if (audit) {
    tbb::parallel_sort(outcome.tested->vertex_face.begin(), outcome.tested->vertex_face.end());
    tbb::parallel_sort(outcome.tested->edge_edge.begin(), outcome.tested->edge_edge.end());
  }
  return outcome;
}

}  // namespace

ElementaryOutcome test_candidates(const MeshTopology& topology, std::span<const AssignmentMask> masks, std::span<const bvh::TrianglePair> candidates,
                                  const StepView& step, const narrowphase::NarrowPhase& narrow_phase, double thickness, bool audit,
                                  bool separation_filter, StageTimes& stages, std::string_view narrow_stage) {
  const auto& x0 = step.x0;
  const auto& x1 = step.x1;
  PrimitiveBoxes boxes;
  tbb::enumerable_thread_specific<Local> locals;
  // The narrow phase on one elementary pair.
  auto test = [&](Local& local, const auto& pair) {
    constexpr bool vertex_face = std::is_same_v<std::decay_t<decltype(pair)>, VertexFacePair>;
    const narrowphase::PairRows rows = pair_rows(topology, x0, x1, pair);
    record_answer(local, pair, rows, vertex_face ? narrow_phase.vertex_face(rows, thickness) : narrow_phase.edge_edge(rows, thickness), audit);
  };
  // The primitives' swept boxes, then every elementary pair of every candidate handed to visit(local, pair), in
  // parallel.
  auto visit_candidates = [&](auto&& visit) {
    boxes = primitive_boxes(topology, x0, x1, thickness);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 64), [&](const auto& range) {
      Local& local = locals.local();
      auto one = [&](const auto& pair) { visit(local, pair); };
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        for_each_elementary_pair(topology, masks, boxes, candidates[i].first, candidates[i].second, one, one);
      }
    });
  };
  // Every candidate's elementary pairs from every thread, less those the separation filter (when `filter`) proves apart.
  auto gather = [&](bool filter) {
    visit_candidates([&](Local& local, const auto& pair) {
      constexpr bool vertex_face = std::is_same_v<std::decay_t<decltype(pair)>, VertexFacePair>;
      if (filter && provably_apart(pair_rows(topology, x0, x1, pair), vertex_face, thickness)) {
        ++local.filtered;
      } else {
        list_of<vertex_face>(local.kept).push_back(pair);
      }
    });
    TestedPairs kept;
    for (Local& local : locals) {
      kept.vertex_face.insert(kept.vertex_face.end(), local.kept.vertex_face.begin(), local.kept.vertex_face.end());
      kept.edge_edge.insert(kept.edge_edge.end(), local.kept.edge_edge.begin(), local.kept.edge_edge.end());
      local.kept = {};
    }
    return kept;
  };
  if (narrow_phase.prefers_batches()) {
    // A narrow phase that answers batches far cheaper than single pairs (an isolated plugin: one round trip to its
    // process per batch): every pair gathered (and filtered), then asked in batches from this thread, in order.
    TestedPairs kept;
    {
      ScopedStageTimer timer(stages, separation_filter ? "distance heuristic" : "gather pairs");
      kept = gather(separation_filter);
      // In pair order, whatever thread found each: the plugin is asked the same questions in the same order on every
      // run and thread count (a plugin that counts its calls answers alike).
      tbb::parallel_sort(kept.vertex_face.begin(), kept.vertex_face.end());
      tbb::parallel_sort(kept.edge_edge.begin(), kept.edge_edge.end());
    }
    ScopedStageTimer timer(stages, narrow_stage);
    Local& local = locals.local();
    ask_in_batches(narrow_phase, topology, step, thickness, kept.vertex_face, local, audit);
    ask_in_batches(narrow_phase, topology, step, thickness, kept.edge_edge, local, audit);
  } else if (!separation_filter) {
    ScopedStageTimer timer(stages, narrow_stage);
    visit_candidates(test);
  } else {
    // The separation filter first, timed on its own as the OpenCL backend times it ("distance heuristic": apccd's
    // front end in the paper), then the narrow phase on the pairs it kept. The same pairs are tested as when both
    // ran in one loop, and the answers do not depend on the order they are tested in.
    TestedPairs kept;
    {
      ScopedStageTimer timer(stages, "distance heuristic");
      kept = gather(true);
    }
    ScopedStageTimer timer(stages, narrow_stage);
    auto test_all = [&](const auto& pairs) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pairs.size(), 16), [&](const auto& range) {
        Local& local = locals.local();
        for (std::size_t i = range.begin(); i != range.end(); ++i) test(local, pairs[i]);
      });
    };
    test_all(kept.vertex_face);
    test_all(kept.edge_edge);
  }
  // The strategy's collision set, assembled from every thread's and put in order: the strategy's own work, timed
  // as its "output" stage (with the thread lists freed), so that no part of the step is in no stage.
  ScopedStageTimer output_timer(stages, "output");
  return assemble_outcome(locals, audit);
}

CollisionSet normalize_in_parallel(std::vector<CollisionSet*> sets) {
  // One sort of everything took one core: 6.8 ms of a 15 ms step with 121,788 pairs on 2 threads (fold, δ = 0.05).
  tbb::parallel_for(std::size_t{0}, sets.size(), [&](std::size_t i) { sets[i]->normalize(); });
  for (std::size_t stride = 1; stride < sets.size(); stride *= 2) {
    tbb::parallel_for(std::size_t{0}, (sets.size() + 2 * stride - 1) / (2 * stride), [&](std::size_t k) {
      const std::size_t i = 2 * k * stride;
      if (i + stride < sets.size()) {
        sets[i]->merge_normalized(*sets[i + stride]);
        *sets[i + stride] = CollisionSet();
      }
    });
  }
  CollisionSet whole;
  if (!sets.empty()) std::swap(whole, *sets.front());
  return whole;
}

void run_narrow_phase(StepResult& result, const MeshTopology& topology, std::span<const AssignmentMask> masks,
                      std::span<const bvh::TrianglePair> candidates, const StepView& step, const narrowphase::NarrowPhase& narrow_phase,
                      double thickness, bool audit, bool separation_filter) {
  ElementaryOutcome outcome =
      test_candidates(topology, masks, candidates, step, narrow_phase, thickness, audit, separation_filter, result.stages, "narrow phase");
  if (separation_filter) result.counters.extra.emplace_back("distance_filtered", static_cast<double>(outcome.filtered));
  result.collisions = std::move(outcome.collisions);
  result.tested = std::move(outcome.tested);
  result.counters.candidate_triangle_pairs = candidates.size();
  result.counters.elementary_tests = outcome.tests;
  result.fault_count += outcome.fault_count;
  for (Fault& fault : outcome.faults) result.faults.push_back(std::move(fault));
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
