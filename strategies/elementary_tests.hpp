#pragma once
/// @file
/// From candidate triangle pairs to tested elementary pairs, by the primitive-assignment masks (docs/DESIGN.md §1):
/// for (A, B), A != B, the vertices A owns against face B, those B owns against face A, and the edges A owns
/// against those B owns, skipping pairs that share a vertex. Every elementary pair comes from exactly one
/// triangle pair, and adjacent triangles still yield the pairs of theirs that share no vertex. Before the narrow
/// phase, the two primitives' swept, δ/2-widened boxes must overlap (a conservative cull; such pairs are not
/// counted as tested).

#include "core/assignment.hpp"
#include "core/scene.hpp"
#include "strategies/bvh/bvh.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

#include <span>
#include <string_view>

namespace ccd::strategies {

struct ElementaryOutcome {
  CollisionSet collisions;
  std::size_t tests = 0;
  /// Pairs the separation filter proved apart (not tested).
  std::size_t filtered = 0;
  std::optional<TestedPairs> tested;
  /// Tests whose narrow phase gave no answer (NarrowPhaseResult::fault), and the first kKeptFaults in pair order.
  std::size_t fault_count = 0;
  std::vector<Fault> faults;
};

/// Tests every elementary pair of `candidates` with `narrow_phase` at `thickness`, in parallel, timed in `stages` as
/// `narrow_stage`. Results are sorted and do not depend on the thread count. With `separation_filter`, pairs that
/// provably_apart() rejects are culled before the narrow phase (counted in `filtered`, not tested), in a pass of
/// their own timed as "distance heuristic".
ElementaryOutcome test_candidates(const MeshTopology& topology, std::span<const AssignmentMask> masks, std::span<const bvh::TrianglePair> candidates,
                                  const StepView& step, const narrowphase::NarrowPhase& narrow_phase, double thickness, bool audit,
                                  bool separation_filter, StageTimes& stages, std::string_view narrow_stage);

/// The last stage of a strategy that hands its candidate triangle pairs to a narrow phase: test_candidates, timed as
/// "narrow phase" (and "distance heuristic"), with its collisions, tested pairs, candidate count and test count
/// stored in `result`. With `separation_filter`, also the counter distance_filtered.
void run_narrow_phase(StepResult& result, const MeshTopology& topology, std::span<const AssignmentMask> masks,
                      std::span<const bvh::TrianglePair> candidates, const StepView& step, const narrowphase::NarrowPhase& narrow_phase,
                      double thickness, bool audit, bool separation_filter = false);

/// One normalized set of several threads' sets (each left emptied): each put in order on its own, in parallel, then
/// merged pairwise in rounds. The same set as appending them all and normalizing once, which takes one core.
CollisionSet normalize_in_parallel(std::vector<CollisionSet*> sets);

/// Appends every elementary pair of triangles a and b, not only those the masks give: their six vertices against
/// the other face and their nine edge pairs, skipping pairs that share a vertex (unsorted; may repeat across calls).
/// What a triangle pair "contains" when a strategy answers with triangle pairs.
void append_all_elementary_pairs(const MeshTopology& topology, FaceId a, FaceId b, TestedPairs& out);

}  // namespace ccd::strategies
