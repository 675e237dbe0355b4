#include "strategies/narrowphase/inclusion.hpp"

#include "strategies/narrowphase/primitive_distance.hpp"

#include "strategies/narrowphase/coplanarity.hpp"
#include "strategies/narrowphase/exact_scaling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <queue>
#include <sstream>

namespace ccd::narrowphase {
namespace {

// The pair as one function of three parameters, F(t, u, v) = S(t) + u·X(t) + v·Y(t), zero when the primitives
// touch:
//   VF: F = p - a - u(b - a) - v(c - a), u, v >= 0, u + v <= 1   (S = p - a, X = a - b, Y = a - c)
//   EE: F = a0 + u(a1 - a0) - b0 - v(b1 - b0), u, v in [0, 1]    (S = a0 - b0, X = a1 - a0, Y = b0 - b1)
// Every position is linear in t, so F is trilinear: over a box of (t, u, v) its values lie in the convex hull of
// its values at the box's 8 corners. The distance between the primitives is the minimum of |F| over the domain,
// so a box whose corner hull misses the ball of radius δ around 0 holds no contact.
//
// Forward error bound (u = 2^-53, M = the largest |coordinate| on this axis over the 8 rows). With
// dx = fl(x1 - x0) computed once, x(t) = fl(x0 + fl(t·dx)) errs by at most |x(t)|u + 2M(2u + u²)(1 + u) < 5.01 uM
// and stays below M(1 + 5.01u). S, X, Y are one rounded difference of two such values: error < 12.03 uM,
// magnitude < 2.01 M. fl(u·X), fl(v·Y) with u, v in [0, 1] add one rounding: < 14.04 uM. The two sums add
// 12.03 + 14.04 + 4.02 (rounding of a value < 4.02 M) and then 14.04 + 6.03: the computed F errs by less than
// 51 uM. We use 64 uM, plus 64 smallest subnormals for products that underflow (added, never multiplied, so
// they hold whatever M is). Pairs arrive rescaled to M < 1 (exact_scaling.hpp; only a pair spanning more than
// about 2^1021 keeps a larger M, below 2^300), so the bound is the same at every scale, and no square below
// underflows unless the pair itself spans more than 2^500.
constexpr double kUnitRoundoff = 0x1p-53;
constexpr double kCornerErrorUnits = 64;      // of u·M, covering the 51 derived above
constexpr double kCornerErrorSubnormals = 64;  // smallest subnormals, for products that underflow
/// Exclusion compares a rounded sum of three squares with a rounded δ²: at most 6 roundings, 6u relative while
/// nothing underflows, which 2^-40 (about 1.6e3 times that) covers.
constexpr double kExclusionRelativeSlack = 0x1p-40;
/// The same 6 roundings when their results are subnormal: each errs by at most half the smallest subnormal.
constexpr double kExclusionSubnormalSlack = 8 * std::numeric_limits<double>::denorm_min();
/// A point proven within δ (stage 2) must be so with this relative room: it only ever adds a false alarm.
constexpr double kProofRelativeSlack = 0x1p-40;
/// Stage 0 calls a pair within δ at t = 0 when its squared distance is below δ² by this much of the squared size:
/// the closest-point distance is computed in a few dozen roundings (<< 1e-10); a mistake here would only be a
/// false alarm with TOI 0, never a miss.
constexpr double kStartDistanceMargin = 1e-10;

struct SubBox {
  double t0, t1, u0, u1, v0, v1;
  std::uint64_t order;  // ties broken by creation order, so the search is deterministic
};

struct LaterFirst {
  bool operator()(const SubBox& a, const SubBox& b) const {
    return a.t0 != b.t0 ? a.t0 > b.t0 : a.order > b.order;
  }
};

/// One query's search: the three stages of InclusionTest.
class InclusionSearch {
 public:
  enum class Verdict { excluded, accepted, split };

  InclusionSearch(const PairRows& rows, double thickness, bool vertex_face, const InclusionSettings& settings)
      : vertex_face_(vertex_face), thickness_(thickness), settings_(settings) {
    Vec3 magnitude = Vec3::Zero(), lower = rows[0], upper = rows[0];
    for (const Vec3& row : rows) {
      magnitude = magnitude.cwiseMax(row.cwiseAbs());
      lower = lower.cwiseMin(row);
      upper = upper.cwiseMax(row);
    }
    for (int k = 0; k < 4; ++k) {
      x0_[k] = rows[k];
      dx_[k] = rows[k + 4] - rows[k];
    }
    error_ = (kCornerErrorUnits * kUnitRoundoff) * magnitude +
             Vec3::Constant(kCornerErrorSubnormals * std::numeric_limits<double>::denorm_min());
    tolerance_ = settings.tolerance * (upper - lower).norm();
    exclusion_bound_ = thickness * thickness * (1 + kExclusionRelativeSlack) + kExclusionSubnormalSlack;
  }

  bool over_budget() { return ++iterations_ > settings_.max_iterations; }

  /// F = S + u·X + v·Y at time t (see the comment above), and the t-derivatives of S, X, Y.
  void terms_at(double t, Vec3& S, Vec3& X, Vec3& Y) const {
    std::array<Vec3, 4> x;
    for (int k = 0; k < 4; ++k) x[k] = x0_[k] + t * dx_[k];
    split_terms(x, S, X, Y);
  }
  void term_rates(Vec3& S, Vec3& X, Vec3& Y) const { split_terms(dx_, S, X, Y); }

  /// The eight corner values of F over a box (corner index = t·4 + u·2 + v).
  std::array<Vec3, 8> corners(const SubBox& box) const {
    Vec3 S[2], X[2], Y[2];
    terms_at(box.t0, S[0], X[0], Y[0]);
    terms_at(box.t1, S[1], X[1], Y[1]);
    std::array<Vec3, 8> F;
    for (int it = 0; it < 2; ++it) {
      for (int iu = 0; iu < 2; ++iu) {
        for (int iv = 0; iv < 2; ++iv) {
          F[it * 4 + iu * 2 + iv] = (S[it] + (iu ? box.u1 : box.u0) * X[it]) + (iv ? box.v1 : box.v0) * Y[it];
        }
      }
    }
    return F;
  }

  /// Excluded (no contact in the box), accepted (every point within δ + tolerance), or split into low/high.
  Verdict examine(const SubBox& box, SubBox& low, SubBox& high, double& achieved) const {
    if (vertex_face_ && box.u0 + box.v0 > 1) return Verdict::excluded;  // exact: 1 is representable
    const std::array<Vec3, 8> F = corners(box);
    Vec3 f_min = F[0], f_max = F[0];
    for (const Vec3& f : F) {
      f_min = f_min.cwiseMin(f);
      f_max = f_max.cwiseMax(f);
    }
    f_min -= error_;
    f_max += error_;
    // Nearest and farthest points of the widened corner box from 0, axis by axis.
    double nearest2 = 0, farthest2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double gap = std::max({f_min[k], -f_max[k], 0.0});
      nearest2 += gap * gap;
      const double far = std::max(std::abs(f_min[k]), std::abs(f_max[k]));
      farthest2 += far * far;
    }
    if (nearest2 > exclusion_bound_) return Verdict::excluded;
    // Split where F changes most (the largest corner difference along a parameter), among the parameters
    // whose interval still halves into two smaller doubles.
    const double bounds[3][2] = {{box.t0, box.t1}, {box.u0, box.u1}, {box.v0, box.v1}};
    double change[3] = {0, 0, 0};
    for (int corner = 0; corner < 8; ++corner) {
      for (int dimension = 0; dimension < 3; ++dimension) {
        const int bit = 4 >> dimension;
        if (corner & bit) change[dimension] = std::max(change[dimension], (F[corner] - F[corner ^ bit]).cwiseAbs().maxCoeff());
      }
    }
    int d = -1;
    for (int dimension = 0; dimension < 3; ++dimension) {
      const double middle = bounds[dimension][0] + (bounds[dimension][1] - bounds[dimension][0]) / 2;
      const bool splittable = bounds[dimension][0] < middle && middle < bounds[dimension][1];
      if (splittable && (d < 0 || change[dimension] > change[d])) d = dimension;
    }
    const double reach = thickness_ + tolerance_;
    if (farthest2 <= reach * reach || d < 0) {
      achieved = std::max(0.0, std::sqrt(farthest2) - thickness_);
      return Verdict::accepted;
    }
    low = box;
    high = box;
    double* lo_bounds[3] = {&low.t1, &low.u1, &low.v1};
    double* hi_bounds[3] = {&high.t0, &high.u0, &high.v0};
    const double middle = bounds[d][0] + (bounds[d][1] - bounds[d][0]) / 2;
    *lo_bounds[d] = middle;
    *hi_bounds[d] = middle;
    low.order = created_++;
    high.order = created_++;
    return Verdict::split;
  }

  /// Stage 2: the time of a contact proven cheaply, or nullopt. Starting from the coplanarity cubic's roots,
  /// Newton steps locate a zero of F; Miranda's theorem then proves one in a small box around it: with A the
  /// inverse Jacobian there, each component G_i of G = A·F is <= 0 on one face of the box across parameter i and
  /// >= 0 on the opposite face. G is trilinear, so its extremes on a face are at the face's corners, which are box
  /// corners. For δ > 0 a domain point with |F| <= δ proves a contact by itself. A mistake here could only add a
  /// false alarm: answers "no" come from exclusions alone.
  std::optional<double> certify() const {
    const std::array<double, 4> cubic = coplanarity_cubic<double>(x0_, dx_, vertex_face_);
    std::array<double, 6> times{};
    const int count = cubic_candidate_times(cubic, times);
    Vec3 dS, dX, dY;
    term_rates(dS, dX, dY);
    std::optional<double> earliest;
    for (int i = 0; i < count; ++i) {
      double t = times[i];
      Vec3 S, X, Y;
      terms_at(t, S, X, Y);
      Eigen::Matrix2d normal;
      normal << X.dot(X), X.dot(Y), X.dot(Y), Y.dot(Y);
      if (!(std::abs(normal.determinant()) > 0)) continue;
      const Eigen::Vector2d uv = normal.inverse() * Eigen::Vector2d(-X.dot(S), -Y.dot(S));
      double u = uv[0], v = uv[1];
      // Resting contacts within δ have no zero of F: try the closest domain point at the candidate time first.
      if (thickness_ > 0) {
        if (const auto within = point_within_thickness(t, u, v)) {
          if (!earliest || *within < *earliest) earliest = within;
          continue;
        }
      }
      Eigen::Matrix3d jacobian;
      for (int newton = 0; newton < 3; ++newton) {
        terms_at(t, S, X, Y);
        jacobian << dS + u * dX + v * dY, X, Y;
        if (!(std::abs(jacobian.determinant()) > 0)) break;
        const Vec3 step = jacobian.inverse() * (S + u * X + v * Y);
        t -= step[0];
        u -= step[1];
        v -= step[2];
      }
      if (!(t >= 0 && t <= 1) || !std::isfinite(u) || !std::isfinite(v)) continue;
      std::optional<double> proven;
      if (thickness_ > 0) proven = point_within_thickness(t, u, v);
      if (!proven) proven = miranda(t, u, v, dS, dX, dY);
      if (proven && (!earliest || *proven < *earliest)) earliest = proven;
    }
    return earliest;
  }

  /// A lower bound of the earliest contact: boxes with t < limit are examined earliest first; the first one that
  /// cannot be excluded (or whatever remains when the budget runs out) bounds the TOI from below.
  double earliest_possible(double limit, long budget) {
    std::priority_queue<SubBox, std::vector<SubBox>, LaterFirst> pending;
    pending.push({0, limit, 0, 1, 0, 1, created_++});
    while (!pending.empty()) {
      if (budget-- <= 0 || over_budget()) return pending.top().t0;
      const SubBox box = pending.top();
      pending.pop();
      SubBox low, high;
      double achieved = 0;
      const Verdict verdict = examine(box, low, high, achieved);
      if (verdict == Verdict::accepted) return box.t0;
      if (verdict == Verdict::split) {
        pending.push(low);
        pending.push(high);
      }
    }
    return limit;
  }

  /// Stage 3: the whole search; see InclusionTest.
  NarrowPhaseResult full_search() {
    NarrowPhaseResult result;
    // Depth first with the earlier half on top: reach a contact (or prove there is none) quickly.
    std::vector<SubBox> stack{{0, 1, 0, 1, 0, 1, created_++}};
    double toi = std::numeric_limits<double>::infinity();
    while (!stack.empty()) {
      if (over_budget()) break;
      const SubBox box = stack.back();
      stack.pop_back();
      SubBox low, high;
      const Verdict verdict = examine(box, low, high, result.achieved_tolerance);
      if (verdict == Verdict::excluded) continue;
      if (verdict == Verdict::accepted) {
        toi = box.t0;
        break;
      }
      stack.push_back(high);
      stack.push_back(low);
    }
    if (stack.empty() && !std::isfinite(toi)) return result;  // every box excluded: proven no contact
    result.collides = true;
    // A contact in a pending box lies at t >= its t0, so the TOI is the smallest t0 of an accepted box or a
    // pending one. Boxes that start earlier than the TOI found so far are examined, earliest first.
    std::priority_queue<SubBox, std::vector<SubBox>, LaterFirst> pending(LaterFirst{}, std::move(stack));
    while (!pending.empty() && pending.top().t0 < toi) {
      if (over_budget()) break;
      const SubBox box = pending.top();
      pending.pop();
      SubBox low, high;
      double achieved = 0;
      const Verdict verdict = examine(box, low, high, achieved);
      if (verdict == Verdict::excluded) continue;
      if (verdict == Verdict::accepted) {
        toi = box.t0;
        result.achieved_tolerance = achieved;
        continue;
      }
      pending.push(low);
      pending.push(high);
    }
    result.hit_iteration_cap = iterations_ > settings_.max_iterations;
    if (result.hit_iteration_cap) result.achieved_tolerance = std::numeric_limits<double>::infinity();
    result.toi = pending.empty() ? toi : std::min(toi, pending.top().t0);
    return result;
  }

 private:
  void split_terms(const std::array<Vec3, 4>& x, Vec3& S, Vec3& X, Vec3& Y) const {
    if (vertex_face_) {
      S = x[0] - x[1];
      X = x[1] - x[2];
      Y = x[1] - x[3];
    } else {
      S = x[0] - x[2];
      X = x[1] - x[0];
      Y = x[2] - x[3];
    }
  }

  bool in_domain(double u, double v) const {
    return u >= 0 && v >= 0 && (vertex_face_ ? u + v <= 1 : u <= 1 && v <= 1);
  }

  std::optional<double> point_within_thickness(double t, double u, double v) const {
    // Clamp into the domain first: any domain point within δ is a contact.
    u = std::clamp(u, 0.0, 1.0);
    v = std::clamp(v, 0.0, 1.0);
    if (vertex_face_ && u + v > 1) {
      const double excess = (u + v - 1) / 2;
      u = std::max(0.0, u - excess);
      v = std::max(0.0, 1 - u);
    }
    if (!in_domain(u, v)) return std::nullopt;
    Vec3 S, X, Y;
    terms_at(t, S, X, Y);
    const double distance = ((S + u * X) + v * Y).norm() + error_.norm();
    if (distance * (1 + kProofRelativeSlack) <= thickness_) return t;
    return std::nullopt;
  }

  std::optional<double> miranda(double t, double u, double v, const Vec3& dS, const Vec3& dX, const Vec3& dY) const {
    constexpr double kHalfWidth = 0x1p-24;  // a box of about 1e-7 in each parameter
    const SubBox box{t - kHalfWidth, t + kHalfWidth, u - kHalfWidth, u + kHalfWidth, v - kHalfWidth, v + kHalfWidth, 0};
    if (box.t0 < 0 || box.t1 > 1 || !in_domain(box.u0, box.v0) || !in_domain(box.u1, box.v1) ||
        !in_domain(box.u0, box.v1) || !in_domain(box.u1, box.v0)) {
      return std::nullopt;
    }
    Vec3 S, X, Y;
    terms_at(t, S, X, Y);
    Eigen::Matrix3d jacobian;
    jacobian << dS + u * dX + v * dY, X, Y;
    if (!(std::abs(jacobian.determinant()) > 0)) return std::nullopt;
    const Eigen::Matrix3d A = jacobian.inverse();
    const Eigen::Matrix3d magnitude = A.cwiseAbs();
    const std::array<Vec3, 8> F = corners(box);
    for (int i = 0; i < 3; ++i) {
      const int bit = 4 >> i;
      bool low_negative = true, low_positive = true, high_negative = true, high_positive = true;
      for (int corner = 0; corner < 8; ++corner) {
        const double g = A.row(i).dot(F[corner]);
        // |A·F_computed - A·F_exact| <= |A|·error, plus the rounding of the 3-term product (< 4u|A||F|).
        const double bound = magnitude.row(i).dot(error_) + 4 * kUnitRoundoff * magnitude.row(i).dot(F[corner].cwiseAbs());
        const bool negative = g + bound < 0, positive = g - bound > 0;
        bool& is_negative = corner & bit ? high_negative : low_negative;
        bool& is_positive = corner & bit ? high_positive : low_positive;
        is_negative = is_negative && negative;
        is_positive = is_positive && positive;
      }
      if (!((low_negative && high_positive) || (low_positive && high_negative))) return std::nullopt;
    }
    return box.t0;
  }

  std::array<Vec3, 4> x0_, dx_;
  bool vertex_face_;
  double thickness_;
  InclusionSettings settings_;
  Vec3 error_;
  double tolerance_ = 0;
  double exclusion_bound_ = 0;
  long iterations_ = 0;
  mutable std::uint64_t created_ = 0;
};

class InclusionTest final : public NarrowPhase {
 public:
  explicit InclusionTest(const InclusionSettings& settings) : settings_(settings) {}

  std::string name() const override {
    std::ostringstream out;
    out << "conservative:tolerance=" << settings_.tolerance << ":max_iterations=" << settings_.max_iterations;
    return out.str();
  }
  bool conservative() const override { return true; }
  NarrowPhaseResult vertex_face(const PairRows& rows, double thickness) const override { return test(rows, thickness, true); }
  NarrowPhaseResult edge_edge(const PairRows& rows, double thickness) const override { return test(rows, thickness, false); }

 private:
  /// Stage 1: the whole domain at once excludes far pairs. Stage 2: a cheap proof of a contact; then only a
  /// lower bound of its TOI is searched, with a small budget. Stage 3: the full search (depth first to a contact
  /// or to proof of none, then earliest first for the TOI).
  NarrowPhaseResult test(const PairRows& original, double thickness_given, bool vertex_face) const {
    const RoundToNearest rounding;
    const std::optional<ScaledPair> scaled = scale_to_unit(original, thickness_given);
    if (!scaled) return {true, 0.0, false, std::numeric_limits<double>::infinity()};  // unscalable: never a miss
    NarrowPhaseResult result = test_scaled(scaled->rows, scaled->thickness, vertex_face);
    result.achieved_tolerance = std::ldexp(result.achieved_tolerance, scaled->exponent);  // back to the pair's units
    return result;
  }

  NarrowPhaseResult test_scaled(const PairRows& rows, double thickness, bool vertex_face) const {
    if (within_thickness_at_start(rows, thickness, vertex_face)) return {true, 0.0, false, 0.0};
    InclusionSearch search(rows, thickness, vertex_face, settings_);
    SubBox low, high;
    double achieved = 0;
    search.over_budget();
    if (search.examine({0, 1, 0, 1, 0, 1, 0}, low, high, achieved) == InclusionSearch::Verdict::excluded) return {};
    if (const auto proven = search.certify()) {
      NarrowPhaseResult result;
      result.collides = true;
      // A contact proven at t = 0 is the earliest there can be; otherwise bound the TOI from below.
      result.toi = *proven <= 0 ? 0.0 : search.earliest_possible(*proven, kToiBudget);
      return result;
    }
    return search.full_search();
  }

  /// Stage 0, for δ > 0: a pair already within δ at t = 0 (resting contact) collides, and 0 is its TOI. The
  /// distance is to a point of each closed primitive, so rounding can only move it by a few ulps of the
  /// coordinates; kStartDistanceMargin of their squared size is far beyond that. At δ = 0 it never fires.
  static bool within_thickness_at_start(const PairRows& r, double thickness, bool vertex_face) {
    if (!(thickness > 0)) return false;
    double scale = 0;
    for (int i = 0; i < 4; ++i) scale = std::max(scale, r[i].cwiseAbs().maxCoeff());
    const double squared = vertex_face ? point_triangle_squared_distance<double>(r[0], r[1], r[2], r[3])
                                       : segment_segment_squared_distance<double>(r[0], r[1], r[2], r[3]);
    return squared <= thickness * thickness - kStartDistanceMargin * scale * scale;
  }

  /// Boxes spent bounding the TOI below once a contact is proven.
  static constexpr long kToiBudget = 48;
  InclusionSettings settings_;
};

}  // namespace

std::unique_ptr<NarrowPhase> make_inclusion(const InclusionSettings& settings) {
  return std::make_unique<InclusionTest>(settings);
}

}  // namespace ccd::narrowphase
