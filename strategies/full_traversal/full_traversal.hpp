#pragma once
/// @file
/// `full`: the baseline APCCD is measured against. Every step: refit every deformable object's BVH over the
/// swept, δ-inflated triangle boxes, traverse fully (self and object pairs as the scene declares), expand the
/// candidates by the assignment masks and run the narrow phase on every elementary pair.
/// With filter=on (`separation_filter`), the separation filter apccd's front end uses (separation_filter.hpp) drops
/// the elementary pairs it proves apart before the narrow phase: the baseline that splits apccd's gain into what
/// the filter gives and what its sessions give. Its name then ends in ":filter=on" (off, the default, is not
/// printed, so that the names of existing results stay).
/// `brute`: every triangle pair the scene lets collide, no culling at all (small scenes): the independent check
/// of culling.

#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

#include <map>
#include <string>

namespace ccd::strategies {

std::unique_ptr<Strategy> make_full_traversal(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase, bool separation_filter = false);

/// Reads full's filter=on|off key from `parameters`, removing it. @throws std::invalid_argument for another value.
bool take_full_filter(std::map<std::string, std::string>& parameters);
std::unique_ptr<Strategy> make_brute_force(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase);

}  // namespace ccd::strategies
