/* The separation filter (strategies/separation_filter.hpp): a cheap, certified "these two primitives stay farther
 * apart than δ during the step", written once for the host and the OpenCL kernels so that `apccd` decides which
 * elementary pairs reach the narrow phase identically on both backends. Double only; every operation is the one the
 * former Eigen code performed, in its order.
 *
 * Error budget. Every decision below compares a computed quantity with a bound that covers its rounding, derived
 * for round-to-nearest (the host sets it on entry; OpenCL devices round to nearest) with unit roundoff u = 2^-53
 * and γ(k) = k·u / (1 - k·u) (Higham, "Accuracy and Stability of Numerical Algorithms", 3.1): a dot product of n
 * terms errs by at most γ(n)·Σ|x_i·y_i| when nothing underflows, and each rounding to a subnormal result adds at
 * most half the smallest subnormal. Pairs arrive rescaled so that every |coordinate| is below 1 (scaling.h's
 * ccd_scale_to_unit), which keeps products far from overflow; subnormal results are covered by the absolute terms.
 * Only a pair spanning more than about 2^1021 keeps larger coordinates (the smallest must stay a normal double);
 * the plane test then declines (see there). */

#ifndef CCD_SHARED_SEPARATION_H
#define CCD_SHARED_SEPARATION_H

#include "strategies/narrowphase/shared/geometry.h"
#include "strategies/narrowphase/shared/scaling.h"

static inline double ccd_gamma(int k) { return k * CCD_UNIT_ROUNDOFF / (1 - k * CCD_UNIT_ROUNDOFF); }
/* A direction whose squared length is below this is useless (its own rounding would dominate): not proven. */
#define CCD_SMALLEST_SQUARED_DIRECTION 0x1p-900

/* An upper bound of |d| for a computed vector d: the sum of squares errs by at most γ(3) of itself, the square root
 * by u; 8u covers both (d's squared length is at least CCD_SMALLEST_SQUARED_DIRECTION, so nothing underflows). */
static inline double ccd_norm_upper(ccd_v3 d) { return ccd_norm(d) * (1 + 8 * CCD_UNIT_ROUNDOFF); }
/* |d|_1, summed left to right. */
static inline double ccd_abs_sum(ccd_v3 d) { return (fabs(d.c[0]) + fabs(d.c[1])) + fabs(d.c[2]); }

/* Whether d separates the two point groups (the first `first_count` rows of each instant, and the rest) by more
 * than δ at every t in [0, 1]. Each projection moves linearly in t, so the gap (lowest of one group minus highest
 * of the other) is concave in t and smallest at an end: checking t = 0 and t = 1 on the exact input rows suffices.
 * Every projection fl(d·x) errs by at most γ(3)·Σ|d_k x_k| + 3 halves of the smallest subnormal
 * <= γ(3)·|d|_1·X + 2·tiny with X = max |coordinate|. The gap is then at least fl(gap)(1 - u) - 2E, and it must
 * exceed δ·|d|; the limit below adds 8u of relative room for its own rounding. */
static inline int ccd_separates(const ccd_v3 r[8], ccd_v3 d, int first_count, double thickness, double largest) {
  if (!(ccd_squared_norm(d) >= CCD_SMALLEST_SQUARED_DIRECTION)) return 0;
  const double projection_error = ccd_gamma(4) * ccd_abs_sum(d) * largest + 2 * CCD_DENORM_MIN;
  const double limit = (thickness * ccd_norm_upper(d) + 2 * projection_error) * (1 + 8 * CCD_UNIT_ROUNDOFF) + 4 * CCD_DENORM_MIN;
  int ab = 1, ba = 1;
  for (int instant = 0; instant <= 4; instant += 4) {
    double low_a = INFINITY, high_a = -INFINITY, low_b = INFINITY, high_b = -INFINITY;
    for (int i = 0; i < 4; ++i) {
      const double x = ccd_dot(d, r[instant + i]);
      if (i < first_count) {
        low_a = ccd_min(low_a, x);
        high_a = ccd_max(high_a, x);
      } else {
        low_b = ccd_min(low_b, x);
        high_b = ccd_max(high_b, x);
      }
    }
    ab = ab && low_b - high_a > limit;
    ba = ba && low_a - high_b > limit;
  }
  return ab || ba;
}

/* A certified lower bound of the distance between the primitives at one instant (positions `x`, each within
 * `position_error` of the exact position per coordinate): the gap along the direction between their computed
 * closest points, over |d|. Any direction gives a lower bound (the primitives are the convex hulls of their
 * corners); the closest-point direction gives nearly the distance. 0 when nothing is proven. */
static inline double ccd_distance_lower_bound(const ccd_v3 x[4], int vertex_face, double largest, double position_error) {
  const ccd_closest closest = vertex_face ? ccd_point_triangle_closest(x[0], x[1], x[2], x[3]) : ccd_segment_segment_closest(x[0], x[1], x[2], x[3]);
  const ccd_v3 d = ccd_sub(closest.second, closest.first);
  if (!(ccd_squared_norm(d) >= CCD_SMALLEST_SQUARED_DIRECTION)) return 0;
  const int first_count = vertex_face ? 1 : 2;
  double high_a = -INFINITY, low_b = INFINITY;
  for (int i = 0; i < 4; ++i) {
    const double p = ccd_dot(d, x[i]);
    if (i < first_count) {
      high_a = ccd_max(high_a, p);
    } else {
      low_b = ccd_min(low_b, p);
    }
  }
  const double absolute_d = ccd_abs_sum(d) * (1 + 4 * CCD_UNIT_ROUNDOFF);
  const double projection_error = ccd_gamma(4) * absolute_d * (largest + position_error) + absolute_d * position_error + 2 * CCD_DENORM_MIN;
  const double gap = (low_b - high_a) * (1 - 2 * CCD_UNIT_ROUNDOFF) - 2 * projection_error;
  if (!(gap > 0)) return 0;
  return gap / ccd_norm_upper(d) * (1 - 4 * CCD_UNIT_ROUNDOFF); /* the division and this product round: 4u covers them */
}

/* Sums of three nonnegative terms, each rounding by u of their magnitude: 4u of the total covers them. */
static inline int ccd_clears(double start, double end, double moved, double thickness) {
  const double bound = (start + end - moved) / 2;
  return bound - 4 * CCD_UNIT_ROUNDOFF * (start + end + moved) > thickness * (1 + 4 * CCD_UNIT_ROUNDOFF) + CCD_DENORM_MIN;
}

/* Every point of a primitive is a fixed convex combination of its corners, so it moves at most as far as its
 * farthest corner, and the distance between the two primitives changes by at most m = mA + mB over the step, at a
 * rate no more than m. With lower bounds of the distances d0, d½, d1 at t = 0, ½, 1, on each half the distance
 * stays above (d_start + d_end - m/2) / 2. Slowly moving pairs just beyond δ (resting near-contacts) are proved
 * apart here, the pairs the narrow phase finds most expensive. The midpoint positions fl(fl(x0 + x1)·½) are within
 * u·X of the exact ones; m is bounded from above (each motion's norm within 8u, as ccd_norm_upper). */
static inline int ccd_apart_by_motion_bound(const ccd_v3 r[8], int vertex_face, double thickness, double largest) {
  const int first_count = vertex_face ? 1 : 2;
  double moved_a = 0, moved_b = 0;
  for (int i = 0; i < 4; ++i) {
    const double moved = ccd_norm(ccd_sub(r[i + 4], r[i]));
    if (i < first_count) {
      moved_a = ccd_max(moved_a, moved);
    } else {
      moved_b = ccd_max(moved_b, moved);
    }
  }
  /* fl(x1 - x0) errs by u per coordinate: its norm by at most u·|x1 - x0|; the norm's own rounding by 8u. */
  const double motion = (moved_a + moved_b) * (1 + 16 * CCD_UNIT_ROUNDOFF) + 4 * CCD_DENORM_MIN;
  const double d0 = ccd_distance_lower_bound(r, vertex_face, largest, 0);
  const double d1 = ccd_distance_lower_bound(r + 4, vertex_face, largest, 0);
  if (!(d0 > thickness) || !(d1 > thickness)) return 0;
  if (ccd_clears(d0, d1, motion, thickness)) return 1;
  ccd_v3 middle[4];
  for (int i = 0; i < 4; ++i) middle[i] = ccd_scale(0.5, ccd_add(r[i], r[i + 4]));
  const double midway = ccd_distance_lower_bound(middle, vertex_face, largest, CCD_UNIT_ROUNDOFF * largest + CCD_DENORM_MIN);
  return ccd_clears(d0, midway, motion / 2, thickness) && ccd_clears(midway, d1, motion / 2, thickness);
}

/* Component-wise |a.y·b.z| + |a.z·b.y|, ...: the cross product evaluated on absolute values. */
static inline ccd_v3 ccd_cross_abs(ccd_v3 a, ccd_v3 b) {
  return ccd_v3_make(fabs(a.c[1] * b.c[2]) + fabs(a.c[2] * b.c[1]), fabs(a.c[2] * b.c[0]) + fabs(a.c[0] * b.c[2]),
                     fabs(a.c[0] * b.c[1]) + fabs(a.c[1] * b.c[0]));
}
/* (a + b) / 2 component-wise. */
static inline ccd_v3 ccd_mean(ccd_v3 a, ccd_v3 b) {
  const ccd_v3 s = ccd_add(a, b);
  return ccd_v3_make(s.c[0] / 2, s.c[1] / 2, s.c[2] / 2);
}

/* The plane (VF) or line (EE) distance |f|/|n| bounds the distance between the primitives from below, with
 * n(t) = B(t) × C(t) and f(t) = n(t)·P(t) (VF p - a against the face's B = b - a, C = c - a; EE b0 - a0 against
 * B = a1 - a0, C = b1 - b0). B, C and P are each linear in t, so they are written in Bernstein form from their
 * values at t = 0 and t = 1, each one rounded difference of exact coordinates (no x1 - x0: a pair translated far
 * during the step keeps its accuracy). Then n has Bernstein control points n0 = B0×C0, n1 = (B0×C1 + B1×C0)/2,
 * n2 = B1×C1 and f = n·P has f0 = n0·P0, f1 = (2 n1·P0 + n0·P1)/3, f2 = (n2·P0 + 2 n1·P1)/3, f3 = n2·P1. By the
 * convex hull property f(t) >= min f_i and |n(t)| <= max |n_j|: if every f_i exceeds δ·max|n_j| (or all lie below
 * its negative), the pair never comes within δ. Each f_i is the same expression evaluated on absolute values
 * (F_i) times at most γ(16) in error: 1 rounding of each difference, 2 of a cross product, 2 of the sum of
 * two, 3 of a dot product, and 2 of the final combination, with room. */
static inline int ccd_apart_from_plane(const ccd_v3 r[8], int vertex_face, double thickness, double largest) {
  /* Its absolute (subnormal) terms hold for |coordinates| < 1: a cross-product entry rounded into the subnormal
   * range is later multiplied by |P| < 2. A pair spanning more than 2^1021 keeps larger coordinates: not proven. */
  if (!(largest < 1)) return 0;
  const int b_to = vertex_face ? 2 : 1, b_from = vertex_face ? 1 : 0, c_from = vertex_face ? 1 : 2;
  const int p_to = vertex_face ? 0 : 2, p_from = vertex_face ? 1 : 0;
  ccd_v3 B[2], C[2], P[2], Pa[2];
  for (int k = 0; k < 2; ++k) {
    B[k] = ccd_sub(r[4 * k + b_to], r[4 * k + b_from]);
    C[k] = ccd_sub(r[4 * k + 3], r[4 * k + c_from]);
    P[k] = ccd_sub(r[4 * k + p_to], r[4 * k + p_from]);
    Pa[k] = ccd_cwise_abs(P[k]);
  }
  ccd_v3 n[3], N[3];
  n[0] = ccd_cross(B[0], C[0]);
  n[1] = ccd_mean(ccd_cross(B[0], C[1]), ccd_cross(B[1], C[0]));
  n[2] = ccd_cross(B[1], C[1]);
  N[0] = ccd_cross_abs(B[0], C[0]);
  N[1] = ccd_mean(ccd_cross_abs(B[0], C[1]), ccd_cross_abs(B[1], C[0]));
  N[2] = ccd_cross_abs(B[1], C[1]);
  double f[4], F[4];
  f[0] = ccd_dot(n[0], P[0]);
  f[1] = (2 * ccd_dot(n[1], P[0]) + ccd_dot(n[0], P[1])) / 3;
  f[2] = (ccd_dot(n[2], P[0]) + 2 * ccd_dot(n[1], P[1])) / 3;
  f[3] = ccd_dot(n[2], P[1]);
  F[0] = ccd_dot(N[0], Pa[0]);
  F[1] = (2 * ccd_dot(N[1], Pa[0]) + ccd_dot(N[0], Pa[1])) / 3;
  F[2] = (ccd_dot(N[2], Pa[0]) + 2 * ccd_dot(N[1], Pa[1])) / 3;
  F[3] = ccd_dot(N[2], Pa[1]);
  /* |n_j| from above: its computed norm plus the error of its components (γ(6)·|N_j|), the norm's rounding 8u. */
  double n_bound = 0;
  for (int j = 0; j < 3; ++j) {
    n_bound = ccd_max(n_bound, (ccd_norm(n[j]) + ccd_gamma(6) * ccd_norm(N[j])) * (1 + 8 * CCD_UNIT_ROUNDOFF) + CCD_DENORM_MIN);
  }
  const double limit = thickness * n_bound * (1 + 4 * CCD_UNIT_ROUNDOFF) + CCD_DENORM_MIN;
  int above = 1, below = 1;
  for (int i = 0; i < 4; ++i) {
    const double error = ccd_gamma(16) * F[i] * (1 + 4 * CCD_UNIT_ROUNDOFF) + 16 * CCD_DENORM_MIN;
    above = above && f[i] - error > limit * (1 + 4 * CCD_UNIT_ROUNDOFF);
    below = below && f[i] + error < -limit * (1 + 4 * CCD_UNIT_ROUNDOFF);
  }
  return above || below;
}

/* 1 only when the pair (rows as step.hpp's pair_rows; modified: rescaled in place) provably stays farther apart
 * than `thickness` during the step. Separating directions first (cheap): the normals at both ends and, within the
 * plane, the perpendiculars of the face's edges (VF) or of both edges (EE); then the plane bound and the motion
 * bound. */
static inline int ccd_provably_apart(ccd_v3 r[8], int vertex_face, double thickness) {
  int exponent = 0;
  if (!ccd_scale_to_unit(r, &thickness, &exponent)) return 0;
  double largest = 0;
  for (int i = 0; i < 8; ++i) largest = ccd_max(largest, ccd_max_coeff(ccd_cwise_abs(r[i])));
  const int first_count = vertex_face ? 1 : 2;
  for (int instant = 0; instant <= 4; instant += 4) {
    const ccd_v3* x = r + instant;
    const ccd_v3 normal = vertex_face ? ccd_cross(ccd_sub(x[2], x[1]), ccd_sub(x[3], x[1])) : ccd_cross(ccd_sub(x[1], x[0]), ccd_sub(x[3], x[2]));
    if (ccd_separates(r, normal, first_count, thickness, largest)) return 1;
    if (vertex_face) {
      for (int k = 0; k < 3; ++k) {
        if (ccd_separates(r, ccd_cross(ccd_sub(x[1 + (k + 1) % 3], x[1 + k]), normal), first_count, thickness, largest)) return 1;
      }
    } else {
      if (ccd_separates(r, ccd_cross(ccd_sub(x[1], x[0]), normal), first_count, thickness, largest)) return 1;
      if (ccd_separates(r, ccd_cross(ccd_sub(x[3], x[2]), normal), first_count, thickness, largest)) return 1;
    }
  }
  return ccd_apart_from_plane(r, vertex_face, thickness, largest) || ccd_apart_by_motion_bound(r, vertex_face, thickness, largest);
}

#endif
