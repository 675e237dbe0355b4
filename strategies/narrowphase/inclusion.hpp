#pragma once
/// @file
/// `conservative`: an inclusion-based bisection over (t, u, v) with a forward error bound, in the spirit of
/// Tight-Inclusion (Wang et al. 2021). It never misses: every answer "no" is proven; "yes" may be a false alarm
/// within the tolerance, or because the iteration cap was hit (reported).

#include "strategies/narrowphase/narrow_phase.hpp"

namespace ccd::narrowphase {

struct InclusionSettings {
  /// Distance tolerance as a fraction of the pair's bounding-box diagonal: a sub-box whose every point lies
  /// within δ + tolerance is reported as a contact.
  double tolerance = 1e-6;
  /// Sub-boxes examined before giving up (and answering "collides").
  long max_iterations = 20000;
};

/// The settings from `conservative`'s spec keys, with the ranges make_narrow_phase checks.
/// @throws std::invalid_argument for an unknown key or a value out of range.
InclusionSettings read_inclusion_settings(const NarrowPhaseParameters& parameters);

std::unique_ptr<NarrowPhase> make_inclusion(const InclusionSettings& settings);

}  // namespace ccd::narrowphase
