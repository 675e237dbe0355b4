#pragma once
/// @file
/// The classic coplanarity-cubic test (Provot 1997; Bridson et al. 2002), in float (`cubic32`) or double
/// (`cubic64`): the four points are coplanar at the roots of a cubic in t; at each root in [0, 1] and at t = 0
/// and t = 1 the primitives' distance is compared with δ + η. Fast; it misses contacts without a sign change of
/// the cubic (tangential double roots, coplanar motion) and near-misses of the tolerance.

#include "strategies/narrowphase/narrow_phase.hpp"

namespace ccd::narrowphase {

struct CubicSettings {
  /// η as a fraction of the pair's bounding-box diagonal: the distance tolerance at the candidate times.
  double eta = 1e-6;
};

/// The settings of `name` (cubic32 or cubic64) from its spec keys, with the ranges make_narrow_phase checks.
/// @throws std::invalid_argument for an unknown key or a value out of range.
CubicSettings read_cubic_settings(const std::string& name, const NarrowPhaseParameters& parameters);

/// `single_precision`: every computation in float (cubic32); otherwise double (cubic64).
std::unique_ptr<NarrowPhase> make_cubic(bool single_precision, const CubicSettings& settings);

}  // namespace ccd::narrowphase
