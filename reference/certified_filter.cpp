#include "reference/certified_filter.hpp"

#include "reference/sign_conditions.hpp"

#include <CGAL/FPU.h>

#include <mpfr.h>

#include <algorithm>
#include <cmath>

namespace ccd::reference {
namespace {}  // namespace

// Rounding down twice (to 53 bits, then to a double, which may be subnormal) stays <= q·2^exponent, and likewise
// upwards; the multiplication by 2^exponent in between is exact (MPFR's exponents reach far beyond double's).
Interval enclosing_interval(const mpq_class& q, long exponent) {
  mpfr_t down, up;
  mpfr_init2(down, 53);
  mpfr_init2(up, 53);
  mpfr_set_q(down, q.get_mpq_t(), MPFR_RNDD);
  mpfr_set_q(up, q.get_mpq_t(), MPFR_RNDU);
  mpfr_mul_2si(down, down, exponent, MPFR_RNDD);
  mpfr_mul_2si(up, up, exponent, MPFR_RNDU);
  const Interval result(mpfr_get_d(down, MPFR_RNDD), mpfr_get_d(up, MPFR_RNDU));
  mpfr_clear(down);
  mpfr_clear(up);
  return result;
}

namespace {

using IntervalVector = Vector3<Interval>;

/// Positions of the four primitive vertices over the time piece `time` (a point or an interval).
struct Positions {
  std::array<IntervalVector, 4> x;
};

Positions positions_over(const std::array<IntervalPoint, 8>& rows, const Interval& time) {
  Positions positions;
  for (int k = 0; k < 4; ++k) {
    const IntervalPoint& a = rows[k];
    const IntervalPoint& b = rows[k + 4];
    positions.x[k] = {a.x + time * (b.x - a.x), a.y + time * (b.y - a.y), a.z + time * (b.z - a.z)};
  }
  return positions;
}

SignCondition<Interval> condition_over(PairKind kind, int index, const Positions& p, const Interval& delta_squared) {
  return kind == PairKind::vertex_face ? vertex_face_condition(index, p.x[0], p.x[1], p.x[2], p.x[3], delta_squared)
                                       : edge_edge_condition(index, p.x[0], p.x[1], p.x[2], p.x[3], delta_squared);
}

/// The separation pre-check, tried before the sign conditions because most enumerated pairs are plainly apart
/// and the conditions cost hundreds of interval products each (on the flag at resolution 100, 1.9 million
/// enumerated pairs per step, 99.5% of them "no", took 88% of the truth's time in the conditions).
///
/// Why it is sound: along any fixed direction d, each vertex's projection d·x(t) is linear in t, so over a time
/// piece the smallest projection of one primitive is concave and the largest of the other convex, and their gap
/// is concave: its values at the piece's two ends bound it from below. A primitive lies in the convex hull of its
/// vertices, so when that gap exceeds δ·|d| at both ends, every point pair is farther apart than δ over the
/// whole piece. The direction may be any vector of doubles (how it was chosen does not matter); the projections,
/// |d| and δ are enclosed by outward-rounded intervals, so the comparison is certified.
class SeparationCheck {
 public:
  SeparationCheck(PairKind kind, const std::array<IntervalPoint, 8>& rows, Interval thickness) : kind_(kind), rows_(rows), thickness_(thickness) {}

  /// True when the pair is farther apart than δ on every piece of [0, 1] after at most `depth` halvings.
  bool apart(int depth) const { return apart(0.0, positions_over(rows_, Interval(0.0)), 1.0, positions_over(rows_, Interval(1.0)), depth); }

 private:
  using Direction = Vector3<double>;
  struct Directions {
    std::array<Direction, 8> d;
    int count = 0;
    /// Non-finite directions (from huge coordinates) are left out: intervals of infinities prove nothing.
    void add(const Direction& v) {
      if (std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z)) d[count++] = v;
    }
  };

  /// The piece [t0, t1] with the positions at its ends; a halving computes only the middle's positions.
  bool apart(double t0, const Positions& start, double t1, const Positions& end, int depth) const {
    if (apart_on_piece(start, end, (t0 + t1) / 2)) return true;
    const double middle = t0 + (t1 - t0) / 2;
    if (depth <= 0 || !(t0 < middle && middle < t1)) return false;
    const Positions at_middle = positions_over(rows_, Interval(middle));
    return apart(t0, start, middle, at_middle, depth - 1) && apart(middle, at_middle, t1, end, depth - 1);
  }

  bool apart_on_piece(const Positions& start, const Positions& end, double t_middle) const {
    const Directions candidates = directions(t_middle);
    for (int i = 0; i < candidates.count; ++i) {
      const Vector3<Interval> d{Interval(candidates.d[i].x), Interval(candidates.d[i].y), Interval(candidates.d[i].z)};
      // Certified upper bound of δ·|d| (rounding is upward here, and sqrt of an upper bound is an upper bound).
      const double reach = (thickness_ * CGAL::sqrt(squared_norm(d))).sup();
      const int side = side_along(d, reach, start);
      if (side != 0 && side_along(d, reach, end) == side) return true;
    }
    return false;
  }

  /// The first primitive is vertex 0 (vertex-face) or vertices 0-1 (edge-edge); the second the rest. +1 when
  /// the second group's projections onto d exceed the first's by more than `reach` (δ·|d|), -1 for the reverse, 0
  /// otherwise. The concavity argument holds for one order only, so both ends must give the same side.
  int side_along(const Vector3<Interval>& d, double reach, const Positions& p) const {
    std::array<Interval, 4> projection;
    for (int k = 0; k < 4; ++k) projection[k] = dot(d, p.x[k]);
    const int split = kind_ == PairKind::vertex_face ? 1 : 2;
    double first_lower = projection[0].inf(), first_upper = projection[0].sup();
    for (int k = 1; k < split; ++k) {
      first_lower = std::min(first_lower, projection[k].inf());
      first_upper = std::max(first_upper, projection[k].sup());
    }
    double second_lower = projection[split].inf(), second_upper = projection[split].sup();
    for (int k = split + 1; k < 4; ++k) {
      second_lower = std::min(second_lower, projection[k].inf());
      second_upper = std::max(second_upper, projection[k].sup());
    }
    const Interval gap_up = Interval(second_lower) - Interval(first_upper);
    const Interval gap_down = Interval(first_lower) - Interval(second_upper);
    if (gap_up.inf() > reach) return 1;
    if (gap_down.inf() > reach) return -1;
    return 0;
  }

  /// Candidate directions at the piece's middle time, in plain doubles: the axes, the line between the two
  /// primitives' centroids, the primitives' common normal and, in that plane, the perpendiculars of the edges
  /// (which separate neighbours lying flat in one sheet).
  Directions directions(double t) const {
    std::array<Direction, 4> x;
    for (int k = 0; k < 4; ++k) {
      const IntervalPoint& a = rows_[k];
      const IntervalPoint& b = rows_[k + 4];
      x[k] = {middle_of(a.x) + t * (middle_of(b.x) - middle_of(a.x)), middle_of(a.y) + t * (middle_of(b.y) - middle_of(a.y)),
              middle_of(a.z) + t * (middle_of(b.z) - middle_of(a.z))};
    }
    Directions out;
    out.add({1, 0, 0});
    out.add({0, 1, 0});
    out.add({0, 0, 1});
    const int split = kind_ == PairKind::vertex_face ? 1 : 2;
    Direction first_centre{0, 0, 0}, second_centre{0, 0, 0};
    for (int k = 0; k < 4; ++k) {
      Direction& centre = k < split ? first_centre : second_centre;
      const double weight = k < split ? 1.0 / split : 1.0 / (4 - split);
      centre = {centre.x + weight * x[k].x, centre.y + weight * x[k].y, centre.z + weight * x[k].z};
    }
    out.add(second_centre - first_centre);
    if (kind_ == PairKind::vertex_face) {
      const Direction n = cross(x[2] - x[1], x[3] - x[1]);
      out.add(n);
      for (int k = 1; k <= 3; ++k) out.add(cross(x[k % 3 + 1] - x[k], n));
    } else {
      const Direction ea = x[1] - x[0], eb = x[3] - x[2];
      const Direction m = cross(ea, eb);
      out.add(m);
      out.add(cross(ea, m));
      out.add(cross(eb, m));
    }
    return out;
  }

  static double middle_of(const Interval& i) { return i.inf() + (i.sup() - i.inf()) / 2; }

  PairKind kind_;
  const std::array<IntervalPoint, 8>& rows_;
  Interval thickness_;
};

enum class Region { excluded, holds, unknown };

bool inside_requirements_hold(const SignCondition<Interval>& c) {
  if (c.has_guard && !(c.guard.inf() > 0)) return false;
  for (int i = 0; i < c.nonnegative_count; ++i) {
    if (!(c.nonnegative[i].inf() >= 0)) return false;
  }
  return true;
}

Region classify(const SignCondition<Interval>& c) {
  if (c.has_guard && c.guard.sup() <= 0) return Region::excluded;
  for (int i = 0; i < c.nonnegative_count; ++i) {
    if (c.nonnegative[i].sup() < 0) return Region::excluded;
  }
  if (c.distance.inf() > 0) return Region::excluded;
  if (inside_requirements_hold(c) && c.distance.sup() <= 0) return Region::holds;
  return Region::unknown;
}

class ConditionExplorer {
 public:
  ConditionExplorer(PairKind kind, int index, const std::array<IntervalPoint, 8>& rows, Interval delta_squared, int max_depth)
      : kind_(kind), index_(index), rows_(rows), delta_squared_(delta_squared), max_depth_(max_depth) {}

  Region explore(double t0, double t1, int depth) const {
    const SignCondition<Interval> over = at(Interval(t0, t1));
    const Region region = classify(over);
    if (region != Region::unknown) return region;
    if (over.has_signed_distance && inside_requirements_hold(over)) {
      const Interval s0 = at(Interval(t0)).signed_distance;
      const Interval s1 = at(Interval(t1)).signed_distance;
      if ((s0.sup() < 0 && s1.inf() > 0) || (s0.inf() > 0 && s1.sup() < 0)) return Region::holds;
    }
    const double middle = t0 + (t1 - t0) / 2;  // any double of [t0, t1] splits soundly
    if (classify(at(Interval(middle))) == Region::holds) return Region::holds;
    if (depth >= max_depth_ || !(t0 < middle && middle < t1)) return Region::unknown;
    const Region left = explore(t0, middle, depth + 1);
    if (left == Region::holds) return Region::holds;
    const Region right = explore(middle, t1, depth + 1);
    if (right == Region::holds) return Region::holds;
    return left == Region::excluded && right == Region::excluded ? Region::excluded : Region::unknown;
  }

 private:
  SignCondition<Interval> at(const Interval& time) const { return condition_over(kind_, index_, positions_over(rows_, time), delta_squared_); }

  PairKind kind_;
  int index_;
  const std::array<IntervalPoint, 8>& rows_;
  Interval delta_squared_;
  int max_depth_;
};

}  // namespace

bool certainly_apart(PairKind kind, const std::array<IntervalPoint, 8>& rows, Interval thickness, int depth) {
  CGAL::Protect_FPU_rounding<true> rounding_upward;
  return SeparationCheck(kind, rows, thickness).apart(depth);
}

FilterVerdict filter_decide(PairKind kind, const std::array<IntervalPoint, 8>& rows, Interval thickness, const FilterSettings& settings) {
  if (settings.separation_depth >= 0 && certainly_apart(kind, rows, thickness, settings.separation_depth)) {
    return FilterVerdict::certainly_no;
  }
  CGAL::Protect_FPU_rounding<true> rounding_upward;
  const Interval delta_squared = CGAL::square(thickness);
  const int count = kind == PairKind::vertex_face ? kVertexFaceConditionCount : kEdgeEdgeConditionCount;
  // Resting contact first: pairs already within δ at the step's start or end (cloth lying on cloth) hold a
  // condition at t = 0 or 1, which the bisection below would only reach after descending to that end.
  for (double end : {0.0, 1.0}) {
    const Positions at_end = positions_over(rows, Interval(end));
    for (int index = 0; index < count; ++index) {
      if (classify(condition_over(kind, index, at_end, delta_squared)) == Region::holds) return FilterVerdict::certainly_yes;
    }
  }
  bool all_excluded = true;
  for (int index = 0; index < count; ++index) {
    const Region region = ConditionExplorer(kind, index, rows, delta_squared, settings.max_depth).explore(0.0, 1.0, 0);
    if (region == Region::holds) return FilterVerdict::certainly_yes;
    all_excluded = all_excluded && region == Region::excluded;
  }
  return all_excluded ? FilterVerdict::certainly_no : FilterVerdict::inconclusive;
}

std::array<IntervalPoint, 8> interval_rows(const std::array<Vec3, 8>& rows) {
  std::array<IntervalPoint, 8> out;
  for (int r = 0; r < 8; ++r) out[r] = {Interval(rows[r].x()), Interval(rows[r].y()), Interval(rows[r].z())};
  return out;
}

std::array<IntervalPoint, 8> interval_rows(const std::array<RationalPoint, 8>& rows) {
  std::array<IntervalPoint, 8> out;
  for (int r = 0; r < 8; ++r) {
    out[r] = {enclosing_interval(rows[r][0]), enclosing_interval(rows[r][1]), enclosing_interval(rows[r][2])};
  }
  return out;
}

}  // namespace ccd::reference
