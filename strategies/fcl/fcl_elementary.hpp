#pragma once
/// @file
/// FCL's own elementary continuous tests (`fcl::detail::Intersect<double>::intersect_VF` / `intersect_EE`, the ones
/// its mesh continuous traversal runs), callable on one query, and an explanation of each "no" they give.
///
/// FCL (0.7) finds the roots of the coplanarity cubic by interval Newton and checks each with an inside test. It
/// has three fixed absolute constants (intersect-inl.h): a cubic whose four coefficients are all within 1e-7 of
/// zero is rejected outright; two edges are "parallel" when |e_a|²|e_b|² - (e_a·e_b)² < 1e-5, and an edge is
/// "degenerate" when every coordinate of it is under 1e-5, both rejected; the inside-triangle test accepts a point
/// up to 1e-5 outside. Being absolute, they depend on the scene's units: the same geometry scaled by a power of two
/// (exact in floating point) can change FCL's answer.

#include "strategies/narrowphase/narrow_phase.hpp"

#include <string_view>

namespace ccd::strategies {

/// FCL's answer, rows in the query order (narrow_phase.hpp). δ = 0 only: FCL has no thickness.
bool fcl_vertex_face(const narrowphase::PairRows& rows);
bool fcl_edge_edge(const narrowphase::PairRows& rows);

/// Why FCL said "no" to a pair that collides.
enum class FclMissCause {
  /// FCL said yes: nothing to explain.
  none,
  /// The four cubic coefficients are all under FCL's 1e-7 near-zero threshold, so the pair is rejected before
  /// any root is sought; scaled up (by a power of two), FCL finds it. Slow or small features in metre-scale scenes.
  near_zero_cubic,
  /// EE only: at every root of the cubic the edges count as parallel or an edge as degenerate under FCL's 1e-5
  /// (a product of squared lengths, so edges shorter than about 0.056 always do); scaled up, FCL finds it.
  parallel_threshold,
  /// The motion is coplanar: the cubic vanishes identically (up to rounding, at every scale), and FCL rejects
  /// every coplanar pair, including those that cross or touch inside the common plane.
  coplanar_motion,
  /// Contact handling: a root exists and is not rejected for scale, but FCL confirms it only by one floating-point
  /// check at the right end of the 1e-7-wide interval it isolated (EE: the closest points of the two lines must lie
  /// within both segments, with no tolerance). A touching contact (distance 0 without crossing: a resting contact
  /// at t = 0, an endpoint grazing an edge) is gone a moment later, so the check fails and the pair is dropped.
  root_rejected,
};

std::string_view to_string(FclMissCause cause);

/// Explains FCL's answer on a pair, by recomputing the quantities its constants apply to and by asking FCL again
/// on the same geometry scaled by 2^10, 2^20 and 2^30.
FclMissCause explain_fcl_answer(const narrowphase::PairRows& rows, bool vertex_face);

}  // namespace ccd::strategies
