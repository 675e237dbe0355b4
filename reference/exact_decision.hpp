#pragma once
/// @file
/// The exact path: every sign condition expanded into polynomials in t with rational coefficients and decided by
/// real root isolation with CGAL's univariate algebraic kernel.

#include "reference/exact_pair.hpp"

#include <optional>

namespace ccd::reference {

/// Result of the exact path: whether the pair collides and, when it does, an isolating interval of the
/// earliest contact time of width <= 2^-toi_bits (toi_bits = 0: no interval is computed).
struct ExactResult {
  bool collides = false;
  std::optional<RationalInterval> toi;
  /// With a TOI: the largest double <= the earliest contact time, decided exactly. A double TOI t is later than
  /// the true one exactly when t > toi_floor (no double lies strictly between toi_floor and the true time).
  std::optional<double> toi_floor;
  /// With a TOI: the smallest double >= the earliest contact time (toi_floor when that time is a double).
  std::optional<double> toi_ceiling;
};

/// Decides exactly. Method, per condition: isolate the real roots in [0, 1] of every polynomial of the
/// condition (polynomials that vanish identically have none and sign 0 everywhere), sort them exactly, and test
/// the signs at t = 0, at every root, at a rational point strictly between neighbouring roots, and at t = 1.
/// Signs are constant between roots, so these points decide the whole interval. The earliest satisfying point
/// (for an open stretch, its left end, which is the infimum and a contact by continuity) is the TOI.
ExactResult decide_exactly(const ExactPair& pair, const mpq_class& thickness, unsigned toi_bits);

}  // namespace ccd::reference
