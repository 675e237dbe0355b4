#pragma once
/// @file
/// `advancement`: conservative advancement by minimum separation (the distance-based test a user with a
/// thickness reaches for). From t = 0 it repeatedly measures the distance d between the primitives and advances
/// by (d - δ)/L, where L bounds how fast that distance can shrink; it reports a contact once d <= δ + η. Over each
/// advance the distance stays above δ, so it cannot step over a contact: it misses only by the rounding of the
/// distance computation. Grazing passes take many steps; the cap then answers "collides".

#include "strategies/narrowphase/narrow_phase.hpp"

namespace ccd::narrowphase {

struct AdvancementSettings {
  /// η as a fraction of the pair's bounding-box diagonal: the distance at which it stops and reports a contact.
  double eta = 1e-6;
  long max_iterations = 1000;
};

std::unique_ptr<NarrowPhase> make_advancement(const AdvancementSettings& settings);

}  // namespace ccd::narrowphase
