#include "reference/certified_filter.hpp"

#include "reference/sign_conditions.hpp"

#include <CGAL/FPU.h>

#include <mpfr.h>

namespace ccd::reference {
namespace {

}  // namespace

// Rounding down twice (to 53 bits, then to a double, which may be subnormal) stays <= q, and likewise upwards.
Interval enclosing_interval(const mpq_class& q) {
  mpfr_t down, up;
  mpfr_init2(down, 53);
  mpfr_init2(up, 53);
  mpfr_set_q(down, q.get_mpq_t(), MPFR_RNDD);
  mpfr_set_q(up, q.get_mpq_t(), MPFR_RNDU);
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
  ConditionExplorer(PairKind kind, int index, const std::array<IntervalPoint, 8>& rows, Interval delta_squared,
                    int max_depth)
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
  SignCondition<Interval> at(const Interval& time) const {
    return condition_over(kind_, index_, positions_over(rows_, time), delta_squared_);
  }

  PairKind kind_;
  int index_;
  const std::array<IntervalPoint, 8>& rows_;
  Interval delta_squared_;
  int max_depth_;
};

}  // namespace

FilterVerdict filter_decide(PairKind kind, const std::array<IntervalPoint, 8>& rows, Interval thickness,
                            const FilterSettings& settings) {
  CGAL::Protect_FPU_rounding<true> rounding_upward;
  const Interval delta_squared = CGAL::square(thickness);
  const int count = kind == PairKind::vertex_face ? kVertexFaceConditionCount : kEdgeEdgeConditionCount;
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
