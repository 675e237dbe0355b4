#pragma once
/// @file
/// What the reference decides: one vertex-face or edge-edge pair (exact_pair.hpp) and a thickness δ >= 0, in exact
/// rationals: the certified filter first, the exact path when it cannot tell.

#include "reference/exact_pair.hpp"

namespace ccd::reference {

/// Decides `pair` at thickness δ (taken as the exact rational it is).
Decision decide(const ExactPair& pair, const mpq_class& thickness, const DecisionRequest& request = {});

/// Convenience: the rows are doubles and δ is a double, all taken exactly.
Decision decide(PairKind kind, const std::array<Vec3, 8>& rows, double thickness, const DecisionRequest& request = {});

}  // namespace ccd::reference
