#include "strategies/separation_filter.hpp"

#include "strategies/narrowphase/coplanarity.hpp"
#include "strategies/narrowphase/primitive_distance.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace ccd::strategies {

namespace {

/// Whether direction d separates the two point groups by more than δ at every t in [0, 1]. Each projection moves
/// linearly in t, so the gap (lowest of one group minus highest of the other) is concave in t and smallest at an
/// end: checking t = 0 and t = 1 suffices. `first` holds the indices (into the rows of one instant) of one group.
bool separates(const narrowphase::PairRows& r, const Vec3& d, int first_count, double thickness, double scale) {
  const double length = d.norm();
  if (!(length > 0)) return false;
  const double limit = thickness * length * (1 + 1e-9) + 1e-9 * length * scale;
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

/// Every point of a primitive is a fixed convex combination of its corners, so it moves at most as far as its
/// farthest corner, and the distance between the two primitives changes by at most m = mA + mB over the step, at a
/// rate no more than m. Knowing the distances d0, d½, d1 at t = 0, ½, 1, on each half the distance stays above
/// (d_start + d_end - m/2) / 2. Slowly moving pairs just beyond δ (resting near-contacts) are proved apart here,
/// the pairs the narrow phase finds most expensive.
bool apart_by_motion_bound(const narrowphase::PairRows& r, bool vertex_face, double thickness, double scale) {
  const int first_count = vertex_face ? 1 : 2;
  double moved_a = 0, moved_b = 0;
  for (int i = 0; i < 4; ++i) {
    double& moved = i < first_count ? moved_a : moved_b;
    moved = std::max(moved, (r[i + 4] - r[i]).norm());
  }
  const double motion = moved_a + moved_b;
  auto distance_at = [&](double t) {
    std::array<Vec3, 4> x;
    for (int i = 0; i < 4; ++i) x[i] = t == 0 ? r[i] : t == 1 ? r[i + 4] : Vec3((1 - t) * r[i] + t * r[i + 4]);
    const double squared = vertex_face ? narrowphase::point_triangle_squared_distance<double>(x[0], x[1], x[2], x[3])
                                       : narrowphase::segment_segment_squared_distance<double>(x[0], x[1], x[2], x[3]);
    return std::sqrt(squared);
  };
  // Rounding of the distances, the interpolated positions and the motions: far below 1e-9 of the coordinates.
  const double limit = thickness + 1e-9 * (scale + motion);
  const double d0 = distance_at(0), d1 = distance_at(1);
  if (d0 <= limit || d1 <= limit) return false;
  if ((d0 + d1 - motion) / 2 > limit) return true;
  const double half = distance_at(0.5);
  return (d0 + half - motion / 2) / 2 > limit && (half + d1 - motion / 2) / 2 > limit;
}

/// The plane (VF) or line (EE) distance |f|/|n| bounds the distance between the primitives from below. By the
/// Bernstein form's convex hull property, f(t) >= min of its Bernstein coefficients and |n(t)| <= max |n's control
/// points|; if f stays above δ·max|n| (or below its negative), the pair never comes within δ.
bool apart_from_plane(const narrowphase::PairRows& r, bool vertex_face, double thickness) {
  std::array<Vec3, 4> x0, dx;
  for (int i = 0; i < 4; ++i) {
    x0[i] = r[i];
    dx[i] = r[i + 4] - r[i];
  }
  const narrowphase::CoplanarityTerms<double> terms(x0, dx, vertex_face);
  const auto [c0, c1, c2, c3] = terms.cubic();
  // Bernstein coefficients on [0, 1].
  const double f[4] = {c0, c0 + c1 / 3, c0 + (2 * c1 + c2) / 3, c0 + c1 + c2 + c3};
  const double n_bound = std::max({terms.n0.norm(), (terms.n0 + terms.n1 / 2).norm(), (terms.n0 + terms.n1 + terms.n2).norm()});
  const double size = std::max(terms.B0.norm(), (terms.B0 + terms.dB).norm()) * std::max(terms.C0.norm(), (terms.C0 + terms.dC).norm());
  const double margin = 1e-9 * size * std::max(terms.P0.norm(), (terms.P0 + terms.dP).norm()) + 1e-300;
  const double limit = thickness * (n_bound + 1e-9 * size) + margin;
  const double lowest = std::min({f[0], f[1], f[2], f[3]});
  const double highest = std::max({f[0], f[1], f[2], f[3]});
  return lowest > limit || highest < -limit;
}

}  // namespace

bool provably_apart(const narrowphase::PairRows& r, bool vertex_face, double thickness) {
  // Separating directions first (cheap): the normals at both ends and, within the plane, the perpendiculars of the
  // face's edges (VF) or of both edges (EE). Rounding of the projections is within 1e-9 of the coordinates' size.
  double scale = 0;
  for (const Vec3& row : r) scale = std::max(scale, row.cwiseAbs().maxCoeff());
  const int first_count = vertex_face ? 1 : 2;
  for (int instant : {0, 4}) {
    const Vec3* x = &r[instant];
    const Vec3 normal = vertex_face ? Vec3((x[2] - x[1]).cross(x[3] - x[1])) : Vec3((x[1] - x[0]).cross(x[3] - x[2]));
    if (separates(r, normal, first_count, thickness, scale)) return true;
    if (vertex_face) {
      for (int k = 0; k < 3; ++k) {
        if (separates(r, (x[1 + (k + 1) % 3] - x[1 + k]).cross(normal), first_count, thickness, scale)) return true;
      }
    } else {
      if (separates(r, (x[1] - x[0]).cross(normal), first_count, thickness, scale)) return true;
      if (separates(r, (x[3] - x[2]).cross(normal), first_count, thickness, scale)) return true;
    }
  }
  return apart_from_plane(r, vertex_face, thickness) || apart_by_motion_bound(r, vertex_face, thickness, scale);
}

}  // namespace ccd::strategies
