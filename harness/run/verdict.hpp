#pragma once
/// @file
/// Judging a strategy's step against the exact truth (docs/DESIGN.md §1, §3, §5): misses (culled or tested), false alarms,
/// TOI accuracy; what each miss was caused by; contact between objects.

#include "core/collision_set.hpp"
#include "core/scene.hpp"
#include "harness/run/records.hpp"
#include "strategies/registry.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <vector>

namespace ccd::harness {

/// TOI accuracy over the truth pairs a strategy reported: `checked` carried a TOI, `missing` did not.
struct ToiVerdict {
  std::size_t checked = 0, late = 0, missing = 0;
  double error_max = 0, error_sum = 0;
  /// Every checked pair's error, for the percentiles a comparison of two runs reads.
  std::vector<double> errors;

  void add(const ToiVerdict& other);
};

/// Misses and false alarms of one step; misses split by whether the strategy tested the pair.
struct Verdict {
  std::size_t missed = 0, culled = 0, tested = 0, false_alarms = 0;
  /// Of `missed`: face-shape pairs.
  std::size_t missed_face_shape = 0;
  ToiVerdict toi;
};

/// Judges one step. A strategy judged by triangle pairs reports in `collisions` every elementary pair its triangle
/// pairs contain, so misses are computed alike; its false alarms are triangle pairs. With `tested` (audit), misses
/// are split into culled and tested; with `toi`, reported TOIs are compared with the truth's exact ones.
Verdict judge(const Scene& scene, const CollisionSet& truth, const strategies::StepResult& result, strategies::Judging judging,
              const strategies::TestedPairs* tested, bool toi);

/// A missed pair as results keep it (a step record's `missed_pairs`): its kind, its ids and its 24 coordinates, so
/// that `compare` can write the pairs a change newly misses as query files without the scene.
MissedPair missed_pair_record(const Scene& scene, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, const VertexFacePair& pair);
MissedPair missed_pair_record(const Scene& scene, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, const EdgeEdgePair& pair);

/// The first `limit` missed pairs of a step (vertex-face, then edge-edge, each in pair order) as records.
std::vector<MissedPair> missed_pair_records(const Scene& scene, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, const CollisionSet& truth,
                                            const CollisionSet& reported, std::size_t limit);

/// What a step reported, in the unit it is judged by.
std::size_t reported_count(const strategies::StepResult& result, strategies::Judging judging);

/// Counts each step's misses by cause ("culled" or "tested" from the audit, or the strategy's own explanation,
/// StrategyEntry::explain_miss) and, with `directory`, writes them as query files (truth 1) under
/// DIRECTORY/vertex-face/CAUSE.csv and DIRECTORY/edge-edge/CAUSE.csv, so a miss can be replayed with
/// `ccdbench queries` and kept in a regression library. Returns {cause: count}.
nlohmann::json record_misses(const Scene& scene, const std::vector<std::vector<Vec3>>& frames, const std::vector<CollisionSet>& truth,
                             const std::vector<strategies::StepResult>& results, const std::vector<strategies::TestedPairs>& tested,
                             const strategies::StrategyEntry& strategy, const std::optional<std::filesystem::path>& directory);

/// Contact between objects, over every step's truth: per object pair "A/B" (A declared first; "A/A" for self
/// contact), the colliding pairs, and the faces of A in contact with B (a face is in contact when one of its corners,
/// edges or itself is in a colliding pair with B: the faces that a face-shape pair would name), summed over steps.
/// What reports/shapes compares between obstacles=mesh and obstacles=shape.
nlohmann::json contact_by_objects(const Scene& scene, const std::vector<CollisionSet>& truth, std::size_t steps);

}  // namespace ccd::harness
