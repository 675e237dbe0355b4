#pragma once
/// @file
/// Face-shape pairs in the strategies (core/shape.hpp says what collides): a cull with libccd that a certified
/// separating axis must confirm, then the project's narrow phases on what survives.
///
/// Cull. The pair is rescaled exactly by a power of two to unit size and taken in the shape's frame: the face's
/// corners relative to the centre move linearly, so at every t the face lies in the convex hull H of its six
/// relative corners at t = 0 and t = 1, and the shape stays at the origin. libccd's GJK asks whether H meets the
/// shape grown by δ and a margin (kGjkMargin). Its "no" is not certified: GJK answers no below an absolute
/// |d|² < DBL_EPSILON, on degenerate simplices and at its iteration limit. So "no" is accepted only where a
/// separating axis, with a bound on every rounding, shows H farther than δ from the shape; otherwise the pair
/// goes on. libccd's "yes" always goes on.
///
/// Narrow phase. Sphere: the vertex-face test with the centre as the vertex and thickness R + δ rounded up. Box:
/// first a certified separating-axis test of the face at t = 0 against the solid box (a face that may meet it
/// collides at t = 0); then the face's corners against the twelve surface triangles, the box's corners against the
/// face and the face's edges against the twelve box edges, with the corners c ± h computed in doubles and δ grown
/// by their rounding (kCornerRounding). A conservative narrow phase thus stays conservative.

#include "core/shape.hpp"
#include "core/step.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

namespace ccd::strategies {

/// Why a cull answered as it did (counters of the strategies; tests check the certified path is taken).
enum class FaceShapeCull {
  /// libccd's GJK found the hull and the grown shape intersecting: the pair goes on.
  gjk_overlap,
  /// GJK said apart and a certified axis agreed: culled.
  certified_apart,
  /// GJK said apart but no candidate axis certified it (or the pair could not be rescaled): the pair goes on.
  uncertified,
};

/// @return certified_apart only when the face provably stays farther than δ from the shape during the step.
/// @param use_gjk false skips libccd and tries the certified axes on every pair (never gjk_overlap then): what
///                benchmarks/face_shape_benchmark.cpp compares, to show what libccd adds.
FaceShapeCull cull_face_shape(const Shape& shape, const FaceShapeRows& rows, double thickness, bool use_gjk = true);

/// Decides the pair with `narrow` (see above). The TOI is the earliest of the elementary tests' (0 for a face that
/// may meet the solid box at t = 0). With `box_prefilter` (the default), a box's 80 elementary pairs are tested
/// only where their sides' swept boxes, widened by half the grown δ, meet; false skips that, for
/// benchmarks/face_shape_benchmark.cpp to attribute it.
narrowphase::NarrowPhaseResult narrow_phase_face_shape(const narrowphase::NarrowPhase& narrow, const Shape& shape, const FaceShapeRows& rows,
                                                       double thickness, bool box_prefilter = true);

/// The face-shape stage of a step, shared by `full`, `apccd` and the OpenCL strategies (on the host): for each shape
/// object and each face of an object that may collide with it, a box test (the face's swept box widened by δ/2
/// against the centre's swept box widened by the shape's size and δ/2, both with bvh::kBoxRoundingMargin), then
/// cull_face_shape, then narrow_phase_face_shape on the survivors. Adds the colliding pairs to result.collisions
/// (normalized again), its time to the stage "face-shape", and the counters face_shape_boxes (pairs past the box
/// test), face_shape_culled (certified apart) and face_shape_tests (narrow-phase decisions). With `audit`, the
/// pairs that reached the narrow phase go to result.tested. Does nothing in a scene without shapes.
void run_face_shape_stage(StepResult& result, const Scene& scene, const StepView& step, const narrowphase::NarrowPhase& narrow, bool audit);

/// R + δ rounded up: the smallest double >= the exact sum (round-to-nearest sum, then one step up when the sum
/// rounded down, found exactly by TwoSum).
double radius_plus_thickness(double radius, double thickness);

}  // namespace ccd::strategies
