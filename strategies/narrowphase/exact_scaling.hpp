#pragma once
/// @file
/// What the conservative tests (the `conservative` narrow phase and the separation filter) do before anything
/// else: run in round-to-nearest, and rescale the pair by a power of two so that its largest |coordinate| lies in
/// [1/2, 1). Multiplying a double by a power of two is exact as long as the result stays a normal double, so the
/// rescaled pair is the same geometric question (and at δ = 0 it has the same truth); DESIGN.md §6 asks that
/// conservative answers do not depend on the scale. At unit scale the tests' error budgets hold with room to
/// spare and no distance underflows: a pair at 2^-960 gets the same answer, at the same cost, as at 2^0.

#include "strategies/narrowphase/narrow_phase.hpp"

#include <optional>

namespace ccd::narrowphase {

/// After rescaling, every |coordinate| is below 2^kLargestScaledExponent even when the pair's own range forces a
/// smaller shift: cubes of differences (the coplanarity terms, up to 6 of them summed) then stay far from overflow.
inline constexpr int kLargestScaledExponent = 300;

struct ScaledPair {
  PairRows rows;
  /// δ·2^-exponent, rounded up when that product is not exact: never smaller than the true scaled δ.
  double thickness;
  /// Lengths of the original pair are lengths of this one times 2^exponent.
  int exponent;
};

/// The pair rescaled exactly: by 2^-e with the largest |coordinate| in [2^(e-1), 2^e), or by the largest power of
/// two that keeps the smallest nonzero |coordinate| a normal double. nullopt when no exact rescaling brings every
/// coordinate below 2^kLargestScaledExponent (a pair spanning about 2^1300 or more), or a coordinate or δ is not
/// finite: conservative callers then answer "collides" / "not proven apart".
std::optional<ScaledPair> scale_to_unit(const PairRows& rows, double thickness);

/// Round-to-nearest for its lifetime, restoring the caller's mode after: the error budgets of the conservative
/// tests assume it, and the reference switches rounding modes in the same process for its interval arithmetic.
class RoundToNearest {
 public:
  RoundToNearest();
  ~RoundToNearest();
  RoundToNearest(const RoundToNearest&) = delete;
  RoundToNearest& operator=(const RoundToNearest&) = delete;

 private:
  int saved_;
};

}  // namespace ccd::narrowphase
