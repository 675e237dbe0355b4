#pragma once
/// @file
/// The certified filter in front of the exact path: interval arithmetic with outward rounding over the same
/// sign conditions (sign_conditions.hpp). It answers "certainly no" or "certainly yes" for the easy pairs and
/// "inconclusive" otherwise; it is never wrong.

#include "reference/exact_pair.hpp"

#include <CGAL/Interval_nt.h>

namespace ccd::reference {

/// CGAL's interval type without its own rounding-mode switching: callers hold a
/// CGAL::Protect_FPU_rounding<true> (rounding towards +infinity) around every operation on it.
using Interval = CGAL::Interval_nt_advanced;

struct IntervalPoint {
  Interval x, y, z;
};

enum class FilterVerdict { certainly_no, certainly_yes, inconclusive };

/// How hard the filter tries before giving up (the exact path then decides).
struct FilterSettings {
  /// Bisection depth over t: [0, 1] is split into at most 2^max_depth pieces per condition. Measured on the
  /// rod-twist sample step (edge-edge candidates): depth 6 leaves 3.5% of pairs inconclusive at 2.9 µs a pair,
  /// depth 12 leaves 0.07% at 4.9 µs; an exact decision costs about 650 µs, so the deeper filter wins.
  int max_depth = 12;
  /// Halvings of [0, 1] for the separation pre-check (0: the whole step as one piece; -1: no pre-check).
  int separation_depth = 6;
};

/// Decides a pair given as intervals that contain its coordinates (point intervals for doubles) and an interval
/// that contains δ. Sets the FPU rounding mode itself.
///
/// Why it is sound: positions over a time piece T = [t0, t1] are enclosed by x0 + T·(x1 - x0) in outward-rounded
/// interval arithmetic, so every condition value is enclosed for every t in T. A condition is ruled out on T when
/// an enclosure proves one of its requirements false everywhere on T; it certainly holds when enclosures prove
/// all requirements at a point, or when the guard and the inside requirements hold on all of T and the signed
/// distance s changes sign between T's ends (then s = 0 somewhere in T, where distance = -δ²·guard <= 0).
FilterVerdict filter_decide(PairKind kind, const std::array<IntervalPoint, 8>& rows, Interval thickness, const FilterSettings& settings = {});

/// The filter's first stage on its own: true when the pair is certainly farther apart than δ over the whole step,
/// proved along a fixed direction on each of at most 2^depth time pieces (see SeparationCheck in the source for
/// why that is sound). False proves nothing. Sets the FPU rounding mode itself.
bool certainly_apart(PairKind kind, const std::array<IntervalPoint, 8>& rows, Interval thickness, int depth);

/// Point intervals of doubles.
std::array<IntervalPoint, 8> interval_rows(const std::array<Vec3, 8>& rows);

/// The tightest intervals of doubles that contain these rationals.
std::array<IntervalPoint, 8> interval_rows(const std::array<RationalPoint, 8>& rows);

/// The tightest interval of doubles that contains q·2^exponent.
Interval enclosing_interval(const mpq_class& q, long exponent = 0);

}  // namespace ccd::reference
