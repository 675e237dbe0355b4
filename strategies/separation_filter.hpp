#pragma once
/// @file
/// A cheap, conservative "these two primitives stay farther apart than δ during the step" test: apccd's front-end
/// distance heuristic at the level of elementary pairs (Wong 2009, front-end filtering).
///
/// For VF (p against face abc) let n(t) = (b-a)×(c-a) and f(t) = n(t)·(p-a); for EE n(t) = ea×eb and
/// f(t) = n(t)·(b0-a0). |f|/|n| is the distance from p to the face's plane (VF) or between the edges' lines (EE),
/// never more than the distance between the primitives. Over t in [0,1], f is a cubic and n a quadratic curve; by
/// the convex hull property of the Bernstein form, f(t) >= min of f's Bernstein coefficients and
/// |n(t)| <= max |n's Bernstein control points|. If f's coefficients all exceed δ·max|n| (or all lie below
/// -δ·max|n|), the pair never comes within δ. Before that, cheaper separating directions: the normals at t = 0 and
/// t = 1 and, in the plane, the perpendiculars of the face's edges (VF) or of both edges (EE). Along a fixed
/// direction every vertex's projection moves linearly, so the gap between the two groups is concave in t and it
/// suffices to check both ends; this separates the in-plane neighbours of a flat cloth, which no plane distance
/// can. Last, a motion bound: certified lower bounds of the distance at t = 0, ½, 1 and how far the primitives can
/// move in between.
///
/// Certified: every comparison carries a bound of its own rounding, derived for round-to-nearest (which it sets on
/// entry), on the pair rescaled exactly by a power of two to unit size (narrowphase/shared/scaling.h), so its
/// answers are the same at every scale from 2^-1000 to 2^1000, tiny coordinates do not underflow and a motion far
/// larger than the features does not enter the rounding (no x1 - x0 is formed where features are compared).
/// It decides "apart" only; "maybe" goes to the narrow phase.

#include "strategies/narrowphase/narrow_phase.hpp"

namespace ccd::strategies {

/// Rows as narrow_phase.hpp. @return true only when the pair provably stays farther apart than `thickness`.
bool provably_apart(const narrowphase::PairRows& rows, bool vertex_face, double thickness);

}  // namespace ccd::strategies
