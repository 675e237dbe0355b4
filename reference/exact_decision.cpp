#include "reference/exact_decision.hpp"

#include "reference/rational_polynomial.hpp"
#include "reference/sign_conditions.hpp"

#include <CGAL/Algebraic_kernel_d_1.h>
#include <CGAL/CORE_arithmetic_kernel.h>

#include <algorithm>
#include <cmath>
#include <mutex>

namespace ccd::reference {
namespace {

using AlgebraicKernel = CGAL::Algebraic_kernel_d_1<CORE::BigInt>;
using IntegerPolynomial = AlgebraicKernel::Polynomial_1;
using AlgebraicReal = AlgebraicKernel::Algebraic_real_1;
using Bound = AlgebraicKernel::Bound;

/// The same polynomial scaled by the positive lcm of its denominators: integer coefficients, same signs.
IntegerPolynomial to_integer_polynomial(const RationalPolynomial& p) {
  mpz_class common = 1;
  for (const mpq_class& c : p.coefficients()) mpz_lcm(common.get_mpz_t(), common.get_mpz_t(), c.get_den_mpz_t());
  std::vector<CORE::BigInt> coefficients;
  coefficients.reserve(p.coefficients().size());
  for (const mpq_class& c : p.coefficients()) {
    const mpz_class scaled = c.get_num() * (common / c.get_den());
    coefficients.emplace_back(scaled.get_mpz_t());
  }
  if (coefficients.empty()) coefficients.emplace_back(0);
  return IntegerPolynomial(coefficients.begin(), coefficients.end());
}

mpq_class to_mpq(const Bound& b) { return mpq_class(b.get_mp()); }

/// One condition in integer polynomials, with the requirement on each sign.
struct ExactCondition {
  enum class Requirement { positive, nonnegative, nonpositive };
  std::vector<std::pair<IntegerPolynomial, Requirement>> polynomials;
  bool impossible = false;  // a guard that vanishes identically never holds
};

/// The distance polynomial comes first: earliest_time() rules a condition out from it alone when it can.
ExactCondition expand(const SignCondition<RationalPolynomial>& c) {
  ExactCondition e;
  using R = ExactCondition::Requirement;
  e.polynomials.emplace_back(to_integer_polynomial(c.distance), R::nonpositive);
  if (c.has_guard) {
    if (c.guard.is_zero()) {
      e.impossible = true;
      return e;
    }
    e.polynomials.emplace_back(to_integer_polynomial(c.guard), R::positive);
  }
  for (int i = 0; i < c.nonnegative_count; ++i) e.polynomials.emplace_back(to_integer_polynomial(c.nonnegative[i]), R::nonnegative);
  return e;
}

bool satisfied(CGAL::Sign sign, ExactCondition::Requirement requirement) {
  switch (requirement) {
    case ExactCondition::Requirement::positive: return sign == CGAL::POSITIVE;
    case ExactCondition::Requirement::nonnegative: return sign != CGAL::NEGATIVE;
    case ExactCondition::Requirement::nonpositive: return sign != CGAL::POSITIVE;
  }
  return false;
}

/// The earliest t in [0, 1] where the condition holds, as an algebraic real; nullopt when it never holds.
std::optional<AlgebraicReal> earliest_time(const ExactCondition& condition) {
  if (condition.impossible) return std::nullopt;
  const AlgebraicKernel kernel;
  const auto solve = kernel.solve_1_object();
  const auto sign_at = kernel.sign_at_1_object();
  const auto compare = kernel.compare_1_object();
  const auto between = kernel.bound_between_1_object();
  const auto construct = kernel.construct_algebraic_real_1_object();

  std::vector<AlgebraicReal> roots;
  for (const auto& [polynomial, requirement] : condition.polynomials) {
    if (CGAL::is_zero(polynomial)) continue;
    std::vector<std::pair<AlgebraicReal, AlgebraicKernel::Multiplicity_type>> found;
    solve(polynomial, Bound(0), Bound(1), std::back_inserter(found));
    // A distance polynomial without roots in [0, 1] keeps its sign there: positive at 0 rules the condition out.
    if (roots.empty() && found.empty() && &polynomial == &condition.polynomials.front().first &&
        sign_at(polynomial, construct(0)) == CGAL::POSITIVE) {
      return std::nullopt;
    }
    for (auto& root : found) roots.push_back(root.first);
  }
  std::sort(roots.begin(), roots.end(), [&](const AlgebraicReal& a, const AlgebraicReal& b) { return compare(a, b) == CGAL::SMALLER; });
  roots.erase(std::unique(roots.begin(), roots.end(), [&](const AlgebraicReal& a, const AlgebraicReal& b) { return compare(a, b) == CGAL::EQUAL; }),
              roots.end());

  // Test points in increasing order: 0, then alternately an open stretch and a root, and finally 1.
  std::vector<AlgebraicReal> breakpoints;
  breakpoints.push_back(construct(0));
  for (const AlgebraicReal& root : roots) {
    if (compare(root, breakpoints.back()) == CGAL::LARGER) breakpoints.push_back(root);
  }
  if (compare(construct(1), breakpoints.back()) == CGAL::LARGER) breakpoints.push_back(construct(1));

  auto holds_at = [&](const AlgebraicReal& t) {
    return std::all_of(condition.polynomials.begin(), condition.polynomials.end(),
                       [&](const auto& entry) { return satisfied(sign_at(entry.first, t), entry.second); });
  };
  for (std::size_t i = 0; i < breakpoints.size(); ++i) {
    if (holds_at(breakpoints[i])) return breakpoints[i];
    if (i + 1 < breakpoints.size() && holds_at(construct(between(breakpoints[i], breakpoints[i + 1])))) {
      return breakpoints[i];  // the infimum of the open stretch
    }
  }
  return std::nullopt;
}

/// The largest double <= t, for t in [0, 1]: from a 64-bit relative approximation (a double or two away, also
/// for tiny t), then corrected by exact comparisons, so it is exact whatever the approximation's rounding. The
/// comparisons refine t's isolating interval only as far as the doubles next to it require.
double floor_to_double(const AlgebraicReal& t) {
  const AlgebraicKernel kernel;
  const auto compare = kernel.compare_1_object();
  auto as_bound = [](double d) { return Bound(mpq_class(d).get_mpq_t()); };
  const auto bounds = kernel.approximate_relative_1_object()(t, 64);
  double floor = std::clamp(to_mpq(bounds.first).get_d(), 0.0, 1.0);  // get_d truncates towards zero
  while (floor > 0 && compare(t, as_bound(floor)) == CGAL::SMALLER) floor = std::nextafter(floor, 0.0);
  for (double next = std::nextafter(floor, 2.0); next <= 1 && compare(t, as_bound(next)) != CGAL::SMALLER; next = std::nextafter(floor, 2.0)) {
    floor = next;
  }
  return floor;
}

/// The smallest double >= t, given the largest double <= t: the same double when t equals it (an exact
/// comparison), else the next one up.
double ceiling_to_double(const AlgebraicReal& t, double floor) {
  const AlgebraicKernel kernel;
  return kernel.compare_1_object()(t, Bound(mpq_class(floor).get_mpq_t())) == CGAL::EQUAL ? floor : std::nextafter(floor, 2.0);
}

Vector3<RationalPolynomial> moving_point(const RationalPoint& at0, const RationalPoint& at1) {
  return {RationalPolynomial::linear(at0[0], at1[0] - at0[0]), RationalPolynomial::linear(at0[1], at1[1] - at0[1]),
          RationalPolynomial::linear(at0[2], at1[2] - at0[2])};
}

/// CGAL's algebraic kernel and CORE keep reference-counted and cached state whose thread safety Debian's
/// CGAL 5.5 does not document; exact decisions are the rare path, so they are serialized.
std::mutex& exact_path_mutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace

ExactResult decide_exactly(const ExactPair& pair, const mpq_class& thickness, unsigned toi_bits) {
  std::array<Vector3<RationalPolynomial>, 4> x;
  for (int k = 0; k < 4; ++k) x[k] = moving_point(pair.rows[k], pair.rows[k + 4]);
  const RationalPolynomial delta_squared(thickness * thickness);

  std::lock_guard lock(exact_path_mutex());
  const AlgebraicKernel kernel;
  const auto compare = kernel.compare_1_object();
  std::optional<AlgebraicReal> earliest;
  const int count = pair.kind == PairKind::vertex_face ? kVertexFaceConditionCount : kEdgeEdgeConditionCount;
  for (int index = 0; index < count; ++index) {
    const SignCondition<RationalPolynomial> condition = pair.kind == PairKind::vertex_face
                                                            ? vertex_face_condition(index, x[0], x[1], x[2], x[3], delta_squared)
                                                            : edge_edge_condition(index, x[0], x[1], x[2], x[3], delta_squared);
    const auto t = earliest_time(expand(condition));
    if (t && (!earliest || compare(*t, *earliest) == CGAL::SMALLER)) earliest = t;
    if (earliest && toi_bits == 0) break;  // the answer is known; no TOI wanted
  }
  ExactResult result;
  result.collides = earliest.has_value();
  if (earliest && toi_bits > 0) {
    const auto bounds = kernel.approximate_absolute_1_object()(*earliest, static_cast<int>(toi_bits));
    result.toi = RationalInterval{to_mpq(bounds.first), to_mpq(bounds.second)};
    result.toi_floor = floor_to_double(*earliest);
    result.toi_ceiling = ceiling_to_double(*earliest, *result.toi_floor);
  }
  return result;
}

}  // namespace ccd::reference
