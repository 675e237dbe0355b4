#include "strategies/separation_filter.hpp"

#include "strategies/narrowphase/exact_scaling.hpp"
#include "strategies/narrowphase/primitive_distance.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace ccd::strategies {

namespace {

using narrowphase::PairRows;

// Error budget. Every decision below compares a computed quantity with a bound that covers its rounding, derived
// for round-to-nearest (set on entry) with unit roundoff u = 2^-53 and γ(k) = k·u / (1 - k·u) (Higham, "Accuracy
// and Stability of Numerical Algorithms", 3.1): a dot product of n terms errs by at most γ(n)·Σ|x_i·y_i| when
// nothing underflows, and each rounding to a subnormal result adds at most half the smallest subnormal. Pairs
// arrive rescaled so that every |coordinate| is below 1 (exact_scaling.hpp), which keeps products far from
// overflow; subnormal results are covered by the absolute terms. Only a pair spanning more than about 2^1021
// keeps larger coordinates (the smallest must stay a normal double); the plane test then declines (see there).
constexpr double kUnit = 0x1p-53;
constexpr double gamma(int k) { return k * kUnit / (1 - k * kUnit); }
constexpr double kTiny = std::numeric_limits<double>::denorm_min();
/// A direction whose squared length is below this is useless (its own rounding would dominate): not proven.
constexpr double kSmallestSquaredDirection = 0x1p-900;

/// An upper bound of |d| for a computed vector d: the sum of squares errs by at most γ(3) of itself, the square
/// root by u; 8u covers both (d's squared length is at least kSmallestSquaredDirection, so nothing underflows).
double norm_upper(const Vec3& d) { return d.norm() * (1 + 8 * kUnit); }

/// Whether d separates the two point groups by more than δ at every t in [0, 1]. Each projection moves linearly
/// in t, so the gap (lowest of one group minus highest of the other) is concave in t and smallest at an end:
/// checking t = 0 and t = 1 on the exact input rows suffices. Every projection fl(d·x) errs by at most
/// γ(3)·Σ|d_k x_k| + 3 halves of the smallest subnormal <= γ(3)·|d|_1·X + 2·kTiny with X = max |coordinate|. The
/// gap is then at least fl(gap)(1 - u) - 2E, and it must exceed δ·|d|; the limit below adds 8u of relative room
/// for its own rounding.
bool separates(const PairRows& r, const Vec3& d, int first_count, double thickness, double largest) {
  if (!(d.squaredNorm() >= kSmallestSquaredDirection)) return false;
  const double projection_error = gamma(4) * d.cwiseAbs().sum() * largest + 2 * kTiny;
  const double limit = (thickness * norm_upper(d) + 2 * projection_error) * (1 + 8 * kUnit) + 4 * kTiny;
  bool ab = true, ba = true;
  for (int instant : {0, 4}) {
    double low_a = INFINITY, high_a = -INFINITY, low_b = INFINITY, high_b = -INFINITY;
    for (int i = 0; i < 4; ++i) {
      const double x = d.dot(r[instant + i]);
      if (i < first_count) {
        low_a = std::min(low_a, x);
        high_a = std::max(high_a, x);
      } else {
        low_b = std::min(low_b, x);
        high_b = std::max(high_b, x);
      }
    }
    ab = ab && low_b - high_a > limit;
    ba = ba && low_a - high_b > limit;
  }
  return ab || ba;
}

/// A certified lower bound of the distance between the primitives at one instant (positions `x`, each within
/// `position_error` of the exact position per coordinate): the gap along the direction between their computed
/// closest points, over |d|. Any direction gives a lower bound (the primitives are the convex hulls of their
/// corners); the closest-point direction gives nearly the distance. 0 when nothing is proven.
double distance_lower_bound(const std::array<Vec3, 4>& x, bool vertex_face, double largest, double position_error) {
  const auto closest = vertex_face ? narrowphase::point_triangle_closest_points<double>(x[0], x[1], x[2], x[3])
                                   : narrowphase::segment_segment_closest_points<double>(x[0], x[1], x[2], x[3]);
  const Vec3 d = closest.second - closest.first;
  if (!(d.squaredNorm() >= kSmallestSquaredDirection)) return 0;
  const int first_count = vertex_face ? 1 : 2;
  double high_a = -INFINITY, low_b = INFINITY;
  for (int i = 0; i < 4; ++i) {
    const double p = d.dot(x[i]);
    if (i < first_count) {
      high_a = std::max(high_a, p);
    } else {
      low_b = std::min(low_b, p);
    }
  }
  const double absolute_d = d.cwiseAbs().sum() * (1 + 4 * kUnit);
  const double projection_error = gamma(4) * absolute_d * (largest + position_error) + absolute_d * position_error + 2 * kTiny;
  const double gap = (low_b - high_a) * (1 - 2 * kUnit) - 2 * projection_error;
  if (!(gap > 0)) return 0;
  return gap / norm_upper(d) * (1 - 4 * kUnit);  // the division and this product round: 4u covers them
}

/// Every point of a primitive is a fixed convex combination of its corners, so it moves at most as far as its
/// farthest corner, and the distance between the two primitives changes by at most m = mA + mB over the step, at a
/// rate no more than m. With lower bounds of the distances d0, d½, d1 at t = 0, ½, 1, on each half the distance
/// stays above (d_start + d_end - m/2) / 2. Slowly moving pairs just beyond δ (resting near-contacts) are proved
/// apart here, the pairs the narrow phase finds most expensive. The midpoint positions fl(fl(x0 + x1)·½) are within
/// u·X of the exact ones; m is bounded from above (each motion's norm within 8u, as norm_upper).
bool apart_by_motion_bound(const PairRows& r, bool vertex_face, double thickness, double largest) {
  const int first_count = vertex_face ? 1 : 2;
  double moved_a = 0, moved_b = 0;
  for (int i = 0; i < 4; ++i) {
    double& moved = i < first_count ? moved_a : moved_b;
    moved = std::max(moved, (r[i + 4] - r[i]).norm());
  }
  // fl(x1 - x0) errs by u per coordinate: its norm by at most u·|x1 - x0|; the norm's own rounding by 8u.
  const double motion = (moved_a + moved_b) * (1 + 16 * kUnit) + 4 * kTiny;
  auto at = [&](int instant) {
    return std::array<Vec3, 4>{r[instant], r[instant + 1], r[instant + 2], r[instant + 3]};
  };
  const double d0 = distance_lower_bound(at(0), vertex_face, largest, 0);
  const double d1 = distance_lower_bound(at(4), vertex_face, largest, 0);
  // Sums of three nonnegative terms, each rounding by u of their magnitude: 4u of the total covers them.
  auto clears = [&](double start, double end, double moved) {
    const double bound = (start + end - moved) / 2;
    return bound - 4 * kUnit * (start + end + moved) > thickness * (1 + 4 * kUnit) + kTiny;
  };
  if (!(d0 > thickness) || !(d1 > thickness)) return false;
  if (clears(d0, d1, motion)) return true;
  std::array<Vec3, 4> middle;
  for (int i = 0; i < 4; ++i) middle[i] = (r[i] + r[i + 4]) * 0.5;
  const double half = distance_lower_bound(middle, vertex_face, largest, kUnit * largest + kTiny);
  return clears(d0, half, motion / 2) && clears(half, d1, motion / 2);
}

/// The plane (VF) or line (EE) distance |f|/|n| bounds the distance between the primitives from below, with
/// n(t) = B(t) × C(t) and f(t) = n(t)·P(t) (VF p - a against the face's B = b - a, C = c - a; EE b0 - a0 against
/// B = a1 - a0, C = b1 - b0). B, C and P are each linear in t, so they are written in Bernstein form from their
/// values at t = 0 and t = 1, each one rounded difference of exact coordinates (no x1 - x0: a pair translated far
/// during the step keeps its accuracy). Then n has Bernstein control points n0 = B0×C0, n1 = (B0×C1 + B1×C0)/2,
/// n2 = B1×C1 and f = n·P has f0 = n0·P0, f1 = (2 n1·P0 + n0·P1)/3, f2 = (n2·P0 + 2 n1·P1)/3, f3 = n2·P1. By the
/// convex hull property f(t) >= min f_i and |n(t)| <= max |n_j|: if every f_i exceeds δ·max|n_j| (or all lie below
/// its negative), the pair never comes within δ. Each f_i is the same expression evaluated on absolute values
/// (F_i) times at most γ(16) in error: 1 rounding of each difference, 2 of a cross product, 2 of the sum of
/// two, 3 of a dot product, and 2 of the final combination, with room.
bool apart_from_plane(const PairRows& r, bool vertex_face, double thickness, double largest) {
  // Its absolute (subnormal) terms hold for |coordinates| < 1: a cross-product entry rounded into the subnormal
  // range is later multiplied by |P| < 2. A pair spanning more than 2^1021 keeps larger coordinates: not proven.
  if (!(largest < 1)) return false;
  auto difference = [&](int to, int from, int instant) { return Vec3(r[instant + to] - r[instant + from]); };
  const int b_to = vertex_face ? 2 : 1, b_from = vertex_face ? 1 : 0, c_from = vertex_face ? 1 : 2;
  const int p_to = vertex_face ? 0 : 2, p_from = vertex_face ? 1 : 0;
  Vec3 B[2], C[2], P[2];
  for (int k = 0; k < 2; ++k) {
    B[k] = difference(b_to, b_from, 4 * k);
    C[k] = difference(3, c_from, 4 * k);
    P[k] = difference(p_to, p_from, 4 * k);
  }
  auto cross_abs = [](const Vec3& a, const Vec3& b) {
    return Vec3(std::abs(a.y() * b.z()) + std::abs(a.z() * b.y()), std::abs(a.z() * b.x()) + std::abs(a.x() * b.z()),
                std::abs(a.x() * b.y()) + std::abs(a.y() * b.x()));
  };
  const Vec3 n[3] = {B[0].cross(C[0]), (B[0].cross(C[1]) + B[1].cross(C[0])) / 2, B[1].cross(C[1])};
  const Vec3 N[3] = {cross_abs(B[0], C[0]), (cross_abs(B[0], C[1]) + cross_abs(B[1], C[0])) / 2, cross_abs(B[1], C[1])};
  const Vec3 Pa[2] = {P[0].cwiseAbs(), P[1].cwiseAbs()};
  const double f[4] = {n[0].dot(P[0]), (2 * n[1].dot(P[0]) + n[0].dot(P[1])) / 3, (n[2].dot(P[0]) + 2 * n[1].dot(P[1])) / 3,
                       n[2].dot(P[1])};
  const double F[4] = {N[0].dot(Pa[0]), (2 * N[1].dot(Pa[0]) + N[0].dot(Pa[1])) / 3,
                       (N[2].dot(Pa[0]) + 2 * N[1].dot(Pa[1])) / 3, N[2].dot(Pa[1])};
  // |n_j| from above: its computed norm plus the error of its components (γ(6)·|N_j|), the norm's rounding 8u.
  double n_bound = 0;
  for (int j = 0; j < 3; ++j) n_bound = std::max(n_bound, (n[j].norm() + gamma(6) * N[j].norm()) * (1 + 8 * kUnit) + kTiny);
  const double limit = thickness * n_bound * (1 + 4 * kUnit) + kTiny;
  bool above = true, below = true;
  for (int i = 0; i < 4; ++i) {
    const double error = gamma(16) * F[i] * (1 + 4 * kUnit) + 16 * kTiny;
    above = above && f[i] - error > limit * (1 + 4 * kUnit);
    below = below && f[i] + error < -limit * (1 + 4 * kUnit);
  }
  return above || below;
}

}  // namespace

bool provably_apart(const PairRows& original, bool vertex_face, double thickness_given) {
  const narrowphase::RoundToNearest rounding;
  const std::optional<narrowphase::ScaledPair> scaled = narrowphase::scale_to_unit(original, thickness_given);
  if (!scaled) return false;
  const PairRows& r = scaled->rows;
  const double thickness = scaled->thickness;
  double largest = 0;
  for (const Vec3& row : r) largest = std::max(largest, row.cwiseAbs().maxCoeff());
  // Separating directions first (cheap): the normals at both ends and, within the plane, the perpendiculars of the
  // face's edges (VF) or of both edges (EE).
  const int first_count = vertex_face ? 1 : 2;
  for (int instant : {0, 4}) {
    const Vec3* x = &r[instant];
    const Vec3 normal = vertex_face ? Vec3((x[2] - x[1]).cross(x[3] - x[1])) : Vec3((x[1] - x[0]).cross(x[3] - x[2]));
    if (separates(r, normal, first_count, thickness, largest)) return true;
    if (vertex_face) {
      for (int k = 0; k < 3; ++k) {
        if (separates(r, (x[1 + (k + 1) % 3] - x[1 + k]).cross(normal), first_count, thickness, largest)) return true;
      }
    } else {
      if (separates(r, (x[1] - x[0]).cross(normal), first_count, thickness, largest)) return true;
      if (separates(r, (x[3] - x[2]).cross(normal), first_count, thickness, largest)) return true;
    }
  }
  return apart_from_plane(r, vertex_face, thickness, largest) || apart_by_motion_bound(r, vertex_face, thickness, largest);
}

}  // namespace ccd::strategies
