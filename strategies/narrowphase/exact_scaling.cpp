#include "strategies/narrowphase/exact_scaling.hpp"

#include <cfenv>
#include <cmath>
#include <limits>

namespace ccd::narrowphase {

std::optional<ScaledPair> scale_to_unit(const PairRows& rows, double thickness) {
  if (!std::isfinite(thickness) || thickness < 0) return std::nullopt;
  double largest = 0, smallest = std::numeric_limits<double>::infinity();
  for (const Vec3& row : rows) {
    for (int k = 0; k < 3; ++k) {
      const double magnitude = std::abs(row[k]);
      if (!std::isfinite(magnitude)) return std::nullopt;
      largest = std::max(largest, magnitude);
      if (magnitude > 0) smallest = std::min(smallest, magnitude);
    }
  }
  if (largest == 0) return ScaledPair{rows, thickness, 0};  // every point at the origin: nothing to rescale
  int largest_exponent = 0, smallest_exponent = 0;
  std::frexp(largest, &largest_exponent);    // largest in [2^(e-1), 2^e)
  std::frexp(smallest, &smallest_exponent);  // smallest in [2^(e-1), 2^e), also for subnormals
  int shift = largest_exponent;
  // Scaling down keeps every bit only while the smallest coordinate stays normal: smallest·2^-shift >= 2^-1022.
  const int keeps_bits = smallest_exponent - 1 + 1022;
  if (shift > keeps_bits) shift = keeps_bits;
  if (largest_exponent - shift > kLargestScaledExponent) return std::nullopt;
  ScaledPair scaled{rows, std::ldexp(thickness, -shift), shift};
  for (Vec3& row : scaled.rows) {
    for (int k = 0; k < 3; ++k) row[k] = std::ldexp(row[k], -shift);
  }
  // δ is not a coordinate: it may lose bits (or overflow). Rounded up, a larger δ only adds false alarms.
  if (std::ldexp(scaled.thickness, shift) < thickness) {
    scaled.thickness = std::nextafter(scaled.thickness, std::numeric_limits<double>::infinity());
  }
  return scaled;
}

RoundToNearest::RoundToNearest() : saved_(std::fegetround()) {
  if (saved_ != FE_TONEAREST) std::fesetround(FE_TONEAREST);
}

RoundToNearest::~RoundToNearest() {
  if (saved_ != FE_TONEAREST) std::fesetround(saved_);
}

}  // namespace ccd::narrowphase
