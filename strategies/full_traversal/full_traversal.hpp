#pragma once
/// @file
/// `full`: the baseline APCCD is measured against. Every step: refit every deformable object's BVH over the
/// swept, δ-inflated triangle boxes, traverse fully (self and object pairs as the scene declares), expand the
/// candidates by the assignment masks and run the narrow phase on every elementary pair.
/// `brute`: every triangle pair the scene lets collide, no culling at all (small scenes): the independent check
/// of culling.

#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

namespace ccd::strategies {

std::unique_ptr<Strategy> make_full_traversal(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase);
std::unique_ptr<Strategy> make_brute_force(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase);

}  // namespace ccd::strategies
