#pragma once
/// @file
/// A pair brought to unit size by a power of two before it is decided (issue 60). Whether a pair collides, and its
/// earliest contact, do not change when every coordinate and δ are multiplied by the same power of two: t is not
/// scaled. Brought to unit size, the pair is the same numbers at every scale, so the certified filter neither
/// underflows nor overflows where it would not at unit size, the exact path's rationals keep the size they have
/// there, and the reference costs the same, and the filter decides the same pairs, at 2^-1000 as at 2^0.
///
/// The exponent is the largest ⌊log2 |x|⌋ over the 24 coordinates and δ (for rationals, up to one more), so the
/// largest of them lies in [1, 2) afterwards (for rationals, in (1/2, 2)); it is the same for a pair of doubles and
/// for the rationals those doubles are, and for the pair times 2^k it is k more. Rationals scale exactly by any
/// power of two. Doubles scale exactly except where a product falls below the normal range and loses bits (a pair
/// whose coordinates span more than double's range): the filter then gets the two doubles around such a product,
/// which enclose it, and the exact path gets the exact rationals, so the answer stays exact.

#include "reference/certified_filter.hpp"
#include "reference/exact_pair.hpp"

#include <utility>

namespace ccd::reference {

/// The exponent e that brings the pair to unit size (the pair is then multiplied by 2^-e): the largest ⌊log2 |x|⌋
/// over the coordinates and δ, 0 when all are zero.
/// @throws std::invalid_argument when a coordinate or δ is not finite.
int unit_scale_exponent(const std::array<Vec3, 8>& rows, double thickness);

/// The same for rationals p/d in lowest terms: the largest (bits of p) - (bits of d), which is ⌊log2 |p/d|⌋ or
/// one more, and exactly the doubles' exponent where the rationals are doubles.
/// @throws std::invalid_argument for a value beyond 2^±(2^30), where MPFR's exponents end.
int unit_scale_exponent(const ExactPair& pair, const mpq_class& thickness);

/// What the certified filter decides on: intervals that contain the coordinates and δ times 2^-exponent.
struct ScaledIntervals {
  std::array<IntervalPoint, 8> rows;
  Interval thickness;
};

/// Point intervals where the product is a double (always, unless it falls below the normal range and loses bits),
/// else the two doubles around it.
ScaledIntervals scaled_intervals(const std::array<Vec3, 8>& rows, double thickness, int exponent);

/// The tightest intervals of doubles that contain the scaled rationals.
ScaledIntervals scaled_intervals(const ExactPair& pair, const mpq_class& thickness, int exponent);

/// The pair and δ times 2^-exponent, exactly: what the exact path decides on.
std::pair<ExactPair, mpq_class> scaled_exactly(ExactPair pair, mpq_class thickness, int exponent);

}  // namespace ccd::reference
