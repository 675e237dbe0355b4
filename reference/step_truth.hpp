#pragma once
/// @file
/// Whole-step ground truth: every VF, EE and face-shape pair of a step that comes within δ, decided exactly.

#include "core/collision_set.hpp"
#include "core/scene.hpp"
#include "core/vec.hpp"

#include <functional>
#include <span>

namespace ccd::reference {

struct TruthRequest {
  /// δ >= 0 (usually the scene's).
  double thickness = 0.0;
  /// Also compute each colliding pair's earliest contact time exactly; the set holds the largest double not after
  /// it (a reported double TOI t is late exactly when t > that value).
  bool with_toi = false;
  /// Called on the calling thread as decisions complete: (pairs decided, pairs to decide).
  std::function<void(std::size_t, std::size_t)> progress;
  /// Time slices of the enumeration (0: chosen from the motion, see compute_step_truth). The answer never depends
  /// on it; tests set it to compare.
  std::size_t time_slices = 0;
};

struct TruthStatistics {
  /// Pairs whose swept, δ-inflated boxes overlap (certified), that the scene lets collide and share no vertex.
  std::size_t vertex_face_pairs = 0;
  std::size_t edge_edge_pairs = 0;
  /// Face-shape pairs whose certified boxes overlap (scenes with shape objects).
  std::size_t face_shape_pairs = 0;
  /// How the pairs were decided.
  std::size_t decided_by_filter = 0;
  std::size_t decided_exactly = 0;
  /// Time slices the enumeration used.
  std::size_t time_slices = 1;
  double enumeration_milliseconds = 0.0;
  double decision_milliseconds = 0.0;
};

struct StepTruth {
  /// Normalized: sorted, no duplicates; TOIs only with with_toi.
  CollisionSet collisions;
  TruthStatistics statistics;
};

/// The truth of one step (x0 -> x1, global numbering of `scene`).
///
/// Enumeration shares no code with the strategies: boxes of each primitive over x0 and x1, widened by δ/2 with
/// outward rounding (so any two primitives that come within δ have overlapping boxes), paired by a sort-and-sweep
/// along the axis of largest extent. When vertices move farther than an edge's extent, the step is cut into 2, 4
/// or 8 time slices with boxes per slice (certified the same way), and the pairs of all slices are merged.
/// Vertices that no face uses are not primitives; VF pairs with v a corner of f and EE pairs with a shared
/// endpoint are adjacent features and never count; self pairs only for objects with self-collision, pairs across
/// objects only for collidable ones. Face-shape pairs: each shape's centre box grown by its size (outward), against
/// the faces of every object the shape may collide with. Every candidate is decided by the certified
/// filter and, where it is inconclusive, exactly. The result does not depend on the thread count.
StepTruth compute_step_truth(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1, const TruthRequest& request);

}  // namespace ccd::reference
