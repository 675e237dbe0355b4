#include "strategies/narrowphase/exact_scaling.hpp"

#include "strategies/narrowphase/shared.hpp"

#include <cfenv>

namespace ccd::narrowphase {

std::optional<ScaledPair> scale_to_unit(const PairRows& rows, double thickness) {
  // shared/inclusion.h's ccd_scale_to_unit, the text the OpenCL kernels compile too.
  auto scaled_rows = shared::to_shared_rows(rows);
  ScaledPair scaled{rows, thickness, 0};
  if (!shared::f64::ccd_scale_to_unit(scaled_rows.data(), &scaled.thickness, &scaled.exponent)) return std::nullopt;
  for (std::size_t i = 0; i < 8; ++i) scaled.rows[i] = shared::from_shared(scaled_rows[i]);
  return scaled;
}

RoundToNearest::RoundToNearest() : saved_(std::fegetround()) {
  if (saved_ != FE_TONEAREST) std::fesetround(FE_TONEAREST);
}

RoundToNearest::~RoundToNearest() {
  if (saved_ != FE_TONEAREST) std::fesetround(saved_);
}

}  // namespace ccd::narrowphase
