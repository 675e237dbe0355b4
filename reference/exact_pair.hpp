#pragma once
/// @file
/// What the reference decides on, and what it answers: one vertex-face or edge-edge pair with linear motion over t in
/// [0, 1], in exact rationals, and a decision. The filter (certified_filter.hpp) and the exact path
/// (exact_decision.hpp) share these; elementary_pair.hpp decides with both.

#include "core/vec.hpp"

#include <gmpxx.h>

#include <array>
#include <optional>

namespace ccd::reference {

enum class PairKind { vertex_face, edge_edge };

using RationalPoint = std::array<mpq_class, 3>;

/// Rows in the data's order: VF v_t0, f0_t0, f1_t0, f2_t0, v_t1, f0_t1, f1_t1, f2_t1;
/// EE ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1.
struct ExactPair {
  PairKind kind = PairKind::vertex_face;
  std::array<RationalPoint, 8> rows;
};

/// The pair whose rows are exactly these doubles (every double is an exact rational).
ExactPair exact_pair_from_doubles(PairKind kind, const std::array<Vec3, 8>& rows);

/// A closed rational interval [lower, upper].
struct RationalInterval {
  mpq_class lower;
  mpq_class upper;
};

struct DecisionRequest {
  /// Try the certified filter first (it may answer; it is never wrong). Off: always the exact path.
  bool use_filter = true;
  /// Also return the earliest contact time (forces the exact path for colliding pairs).
  bool want_toi = false;
  /// Width of the returned TOI interval: at most 2^-toi_bits.
  unsigned toi_bits = 64;
};

enum class DecidedBy { filter, exact };

struct Decision {
  /// Whether the distance between the closed primitives is <= δ for some t in [0, 1]. Always exact.
  bool collides = false;
  DecidedBy decided_by = DecidedBy::exact;
  /// With want_toi and collides: an interval that contains the earliest such t.
  std::optional<RationalInterval> toi;
  /// With want_toi and collides: the largest double <= the earliest such t, exactly. A double TOI is later than
  /// the true one exactly when it is greater than this.
  std::optional<double> toi_floor;
  /// With want_toi and collides: the smallest double >= the earliest such t (toi_floor when t is a double).
  std::optional<double> toi_ceiling;
};

}  // namespace ccd::reference
