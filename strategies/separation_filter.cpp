#include "strategies/separation_filter.hpp"

#include <algorithm>
#include <cmath>

namespace ccd::strategies {

bool apart_from_plane(const narrowphase::PairRows& r, bool vertex_face, double thickness);

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
  return apart_from_plane(r, vertex_face, thickness);
}

bool apart_from_plane(const narrowphase::PairRows& r, bool vertex_face, double thickness) {
  // x(t) = x0 + t·dx for the three difference vectors B, C (spanning n) and P (to the point / other line).
  const Vec3 B0 = vertex_face ? Vec3(r[2] - r[1]) : Vec3(r[1] - r[0]);
  const Vec3 C0 = vertex_face ? Vec3(r[3] - r[1]) : Vec3(r[3] - r[2]);
  const Vec3 P0 = vertex_face ? Vec3(r[0] - r[1]) : Vec3(r[2] - r[0]);
  const Vec3 B1 = vertex_face ? Vec3(r[6] - r[5]) : Vec3(r[5] - r[4]);
  const Vec3 C1 = vertex_face ? Vec3(r[7] - r[5]) : Vec3(r[7] - r[6]);
  const Vec3 P1 = vertex_face ? Vec3(r[4] - r[5]) : Vec3(r[6] - r[4]);
  const Vec3 dB = B1 - B0, dC = C1 - C0, dP = P1 - P0;
  // n(t) = n0 + n1 t + n2 t², f(t) = n(t)·P(t) = c0 + c1 t + c2 t² + c3 t³.
  const Vec3 n0 = B0.cross(C0), n1 = B0.cross(dC) + dB.cross(C0), n2 = dB.cross(dC);
  const double c0 = n0.dot(P0), c1 = n0.dot(dP) + n1.dot(P0), c2 = n1.dot(dP) + n2.dot(P0), c3 = n2.dot(dP);
  // Bernstein coefficients on [0, 1].
  const double f[4] = {c0, c0 + c1 / 3, c0 + (2 * c1 + c2) / 3, c0 + c1 + c2 + c3};
  const double n_bound = std::max({n0.norm(), (n0 + n1 / 2).norm(), (n0 + n1 + n2).norm()});
  const double size = std::max(B0.norm(), B1.norm()) * std::max(C0.norm(), C1.norm());
  const double margin = 1e-9 * size * std::max(P0.norm(), P1.norm()) + 1e-300;
  const double limit = thickness * (n_bound + 1e-9 * size) + margin;
  const double lowest = std::min({f[0], f[1], f[2], f[3]});
  const double highest = std::max({f[0], f[1], f[2], f[3]});
  return lowest > limit || highest < -limit;
}

}  // namespace ccd::strategies
