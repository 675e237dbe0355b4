/* `conservative`, the inclusion-based narrow phase, written once for the host and the OpenCL backend (geometry.h
 * says how the two stay bit-identical). Double only: ccd_real = double, with a 64-bit unsigned `ccd_ulong` and the
 * functions sqrt, fabs, frexp, ldexp, nextafter and isfinite from its environment.
 *
 * The pair as one function of three parameters, F(t, u, v) = S(t) + u·X(t) + v·Y(t), zero when the primitives
 * touch:
 *   VF: F = p - a - u(b - a) - v(c - a), u, v >= 0, u + v <= 1   (S = p - a, X = a - b, Y = a - c)
 *   EE: F = a0 + u(a1 - a0) - b0 - v(b1 - b0), u, v in [0, 1]    (S = a0 - b0, X = a1 - a0, Y = b0 - b1)
 * Every position is linear in t, so F is trilinear: over a box of (t, u, v) its values lie in the convex hull of
 * its values at the box's 8 corners. The distance between the primitives is the minimum of |F| over the domain,
 * so a box whose corner hull misses the ball of radius δ around 0 holds no contact.
 *
 * Forward error bound (u = 2^-53, M = the largest |coordinate| on this axis over the 8 rows). With
 * dx = fl(x1 - x0) computed once, x(t) = fl(x0 + fl(t·dx)) errs by at most |x(t)|u + 2M(2u + u²)(1 + u) < 5.01 uM
 * and stays below M(1 + 5.01u). S, X, Y are one rounded difference of two such values: error < 12.03 uM,
 * magnitude < 2.01 M. fl(u·X), fl(v·Y) with u, v in [0, 1] add one rounding: < 14.04 uM. The two sums add
 * 12.03 + 14.04 + 4.02 (rounding of a value < 4.02 M) and then 14.04 + 6.03: the computed F errs by less than
 * 51 uM. We use 64 uM, plus 64 smallest subnormals for products that underflow (added, never multiplied, so
 * they hold whatever M is). Pairs arrive rescaled to M < 1 (ccd_scale_to_unit; only a pair spanning more than
 * about 2^1021 keeps a larger M, below 2^300), so the bound is the same at every scale, and no square below
 * underflows unless the pair itself spans more than 2^500. The bound assumes round-to-nearest, IEEE double
 * arithmetic with subnormals and no contraction: the OpenCL backend checks its device for exactly that before
 * use (strategies/opencl/kernels/self_test.cl). */
#ifndef CCD_SHARED_INCLUSION_H
#define CCD_SHARED_INCLUSION_H

#include "strategies/narrowphase/shared/geometry.h"
#include "strategies/narrowphase/shared/scaling.h"
#include "strategies/narrowphase/shared/sub_boxes.h"

/* of u·M, covering the 51 derived above */
#define CCD_CORNER_ERROR_UNITS 64.0
/* smallest subnormals, for products that underflow */
#define CCD_CORNER_ERROR_SUBNORMALS 64.0
/* Exclusion compares a rounded sum of three squares with a rounded δ²: at most 6 roundings, 6u relative while
 * nothing underflows, which 2^-40 (about 1.6e3 times that) covers. */
#define CCD_EXCLUSION_RELATIVE_SLACK 0x1p-40
/* The same 6 roundings when their results are subnormal: each errs by at most half the smallest subnormal. */
#define CCD_EXCLUSION_SUBNORMAL_SLACK (8.0 * CCD_DENORM_MIN)
/* A point proven within δ (stages 3 and 4) must be so with this relative room: it only ever adds a false alarm. */
#define CCD_PROOF_RELATIVE_SLACK 0x1p-40
/* Stage 0 calls a pair within δ at t = 0 when its squared distance is below δ² by this much of the squared size:
 * the closest-point distance is computed in a few dozen roundings (<< 1e-10); a mistake here would only be a false
 * alarm with TOI 0, never a miss. */
#define CCD_START_DISTANCE_MARGIN 1e-10
/* Half-width of the box around a Newton point in which Miranda's theorem proves a zero: about 1e-7 per parameter. */
#define CCD_MIRANDA_HALF_WIDTH 0x1p-24

/* ---- The inclusion search. ---- */

typedef struct {
  ccd_v3 x0[4], dx[4];
  /* The rows at t = 1 as given (x0 + dx rounds: stage 2's error bound is for the given rows). */
  ccd_v3 x1[4];
  int vertex_face;
  double thickness;
  double tolerance_fraction;
  /* Longest time span, a fraction of the step, of a box accepted as the contact, and the largest gap between a
   * proven contact and the TOI reported for it (stage 4). */
  double toi_tolerance;
  long max_iterations;
  ccd_v3 error;
  double tolerance;
  double exclusion_bound;
  long iterations;
  ccd_ulong created;
  /* Iterations after which the search gives up and reports an overflow (0: never): the OpenCL backend hands long
   * queries to the host, which runs them again from the start without the limit. */
  long give_up_after;
  int gave_up;
} ccd_inclusion;

enum { CCD_EXCLUDED = 0, CCD_ACCEPTED = 1, CCD_SPLIT = 2 };

static inline void ccd_inclusion_init(ccd_inclusion* s, const ccd_v3 rows[8], double thickness, int vertex_face, double tolerance_fraction,
                                      double toi_tolerance, long max_iterations) {
  ccd_v3 magnitude = ccd_v3_make(0, 0, 0), lower = rows[0], upper = rows[0];
  for (int i = 0; i < 8; ++i) {
    magnitude = ccd_cwise_max(magnitude, ccd_cwise_abs(rows[i]));
    lower = ccd_cwise_min(lower, rows[i]);
    upper = ccd_cwise_max(upper, rows[i]);
  }
  for (int k = 0; k < 4; ++k) {
    s->x0[k] = rows[k];
    s->dx[k] = ccd_sub(rows[k + 4], rows[k]);
    s->x1[k] = rows[k + 4];
  }
  s->vertex_face = vertex_face;
  s->thickness = thickness;
  s->tolerance_fraction = tolerance_fraction;
  s->toi_tolerance = toi_tolerance;
  s->max_iterations = max_iterations;
  for (int k = 0; k < 3; ++k) {
    s->error.c[k] = (CCD_CORNER_ERROR_UNITS * CCD_UNIT_ROUNDOFF) * magnitude.c[k] + CCD_CORNER_ERROR_SUBNORMALS * CCD_DENORM_MIN;
  }
  s->tolerance = tolerance_fraction * ccd_norm(ccd_sub(upper, lower));
  s->exclusion_bound = thickness * thickness * (1 + CCD_EXCLUSION_RELATIVE_SLACK) + CCD_EXCLUSION_SUBNORMAL_SLACK;
  s->iterations = 0;
  s->created = 0;
  s->give_up_after = 0;
  s->gave_up = 0;
}

static inline int ccd_over_budget(ccd_inclusion* s) {
  ++s->iterations;
  if (s->give_up_after > 0 && s->iterations > s->give_up_after) {
    s->gave_up = 1;
    return 1;
  }
  return s->iterations > s->max_iterations;
}

/* S, X, Y of F = S + u·X + v·Y from four points (see the top of this file). */
static inline void ccd_split_terms(const ccd_inclusion* s, const ccd_v3 x[4], ccd_v3* S, ccd_v3* X, ccd_v3* Y) {
  if (s->vertex_face) {
    *S = ccd_sub(x[0], x[1]);
    *X = ccd_sub(x[1], x[2]);
    *Y = ccd_sub(x[1], x[3]);
  } else {
    *S = ccd_sub(x[0], x[2]);
    *X = ccd_sub(x[1], x[0]);
    *Y = ccd_sub(x[2], x[3]);
  }
}
static inline void ccd_terms_at(const ccd_inclusion* s, double t, ccd_v3* S, ccd_v3* X, ccd_v3* Y) {
  ccd_v3 x[4];
  for (int k = 0; k < 4; ++k) x[k] = ccd_along(s->x0[k], t, s->dx[k]);
  ccd_split_terms(s, x, S, X, Y);
}
static inline ccd_v3 ccd_f_value(ccd_v3 S, double u, ccd_v3 X, double v, ccd_v3 Y) { return ccd_add(ccd_add(S, ccd_scale(u, X)), ccd_scale(v, Y)); }

/* The eight corner values of F over a box (corner index = t·4 + u·2 + v). */
static inline void ccd_corners(const ccd_inclusion* s, const ccd_sub_box* box, ccd_v3 F[8]) {
  ccd_v3 S[2], X[2], Y[2];
  ccd_terms_at(s, box->t0, &S[0], &X[0], &Y[0]);
  ccd_terms_at(s, box->t1, &S[1], &X[1], &Y[1]);
  for (int it = 0; it < 2; ++it) {
    for (int iu = 0; iu < 2; ++iu) {
      for (int iv = 0; iv < 2; ++iv) F[it * 4 + iu * 2 + iv] = ccd_f_value(S[it], iu ? box->u1 : box->u0, X[it], iv ? box->v1 : box->v0, Y[it]);
    }
  }
}

static inline double ccd_box_bound(const ccd_sub_box* box, int dimension, int high) {
  if (dimension == 0) return high ? box->t1 : box->t0;
  if (dimension == 1) return high ? box->u1 : box->u0;
  return high ? box->v1 : box->v0;
}
static inline void ccd_set_box_bound(ccd_sub_box* box, int dimension, int high, double value) {
  if (dimension == 0) {
    if (high)
      box->t1 = value;
    else
      box->t0 = value;
  } else if (dimension == 1) {
    if (high)
      box->u1 = value;
    else
      box->u0 = value;
  } else {
    if (high)
      box->v1 = value;
    else
      box->v0 = value;
  }
}

/* VF: the vertices of a (u, v) box's part inside the triangle u + v <= 1 (at most 5), in order around it, where
 * the box reaches past the hypotenuse. F is affine in (u, v) at each t and linear in t at each (u, v), so over the
 * part times [t0, t1] its values lie in the convex hull of its values at these vertices at t0 and at t1, as over a
 * box they lie in the hull of its corners' (the error bound is the same: every u, v is in [0, 1]). A corner whose
 * rounded u + v is at most 1 counts as inside (the sum rounds to 1 only from within an ulp of it); the hypotenuse
 * crosses an edge at 1 - (the edge's fixed coordinate), taken one double further out (toward the outer corner),
 * so that the vertices enclose the exact part. Writes 2 × count values (t0's, then t1's); returns 2 × count. */
#define CCD_CLIPPED_VERTICES 5
static inline int ccd_clipped_values(const ccd_inclusion* s, const ccd_sub_box* box, ccd_v3* values) {
  const double cu[4] = {box->u0, box->u1, box->u1, box->u0}, cv[4] = {box->v0, box->v0, box->v1, box->v1};
  double pu[CCD_CLIPPED_VERTICES], pv[CCD_CLIPPED_VERTICES];
  int count = 0;
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) & 3;
    const int in_i = cu[i] + cv[i] <= 1, in_j = cu[j] + cv[j] <= 1;
    if (in_i && count < CCD_CLIPPED_VERTICES) {
      pu[count] = cu[i];
      pv[count] = cv[i];
      ++count;
    }
    if (in_i != in_j && count < CCD_CLIPPED_VERTICES) {
      if (cv[i] == cv[j]) { /* an edge along u at v = cv[i] */
        pu[count] = ccd_clamp(nextafter(1 - cv[i], 2.0), box->u0, box->u1);
        pv[count] = cv[i];
      } else { /* an edge along v at u = cu[i] */
        pu[count] = cu[i];
        pv[count] = ccd_clamp(nextafter(1 - cu[i], 2.0), box->v0, box->v1);
      }
      ++count;
    }
  }
  ccd_v3 S[2], X[2], Y[2];
  ccd_terms_at(s, box->t0, &S[0], &X[0], &Y[0]);
  ccd_terms_at(s, box->t1, &S[1], &X[1], &Y[1]);
  for (int it = 0; it < 2; ++it) {
    for (int i = 0; i < count; ++i) values[it * count + i] = ccd_f_value(S[it], pu[i], X[it], pv[i], Y[it]);
  }
  return 2 * count;
}

/* Whether a VF box reaches past the hypotenuse u + v = 1, and is tested on its part inside the triangle (rounding up
 * counts a corner in, which only enlarges the part). */
static inline int ccd_clips(const ccd_inclusion* s, const ccd_sub_box* box) { return s->vertex_face && box->u1 + box->v1 > 1; }

/* F's values whose convex hull holds F over the box (its corners', or its part inside the triangle's for a VF box
 * across the hypotenuse); returns their count. */
static inline int ccd_box_values(const ccd_inclusion* s, const ccd_sub_box* box, ccd_v3* values) {
  if (ccd_clips(s, box)) return ccd_clipped_values(s, box, values);
  ccd_corners(s, box, values);
  return 8;
}

/* |v|, never below it: v is first scaled exactly by a power of two to a largest component in [1/2, 1), so that no
 * square underflows (a component of 2^-540 squares to 0, and |v| came out 0 for an edge that short), then the
 * rounded norm (a few u) is raised by 2^-50 and scaled back. 0 for v = 0, and NaN for a NaN component. */
static inline double ccd_norm_above(ccd_v3 v) {
  const double largest = ccd_max_coeff(ccd_cwise_abs(v));
  if (largest == 0) return 0.0;
  if (!(largest > 0)) return largest; /* NaN */
  /* Where no square can underflow harmfully or overflow (the rest of the range), the scaling is exact and changes
   * nothing: the same value without its library calls (this is on the search's every box). */
  if (largest >= 0x1p-500 && largest <= 0x1p500) return ccd_norm(v) * (1 + 0x1p-50);
  int exponent = 0;
  frexp(largest, &exponent);
  const ccd_v3 w = ccd_v3_make(ldexp(v.c[0], -exponent), ldexp(v.c[1], -exponent), ldexp(v.c[2], -exponent));
  return ldexp(ccd_norm(w) * (1 + 0x1p-50), exponent);
}

/* Whether the plane normal to n at distance δ from 0 separates the box's values from the ball of radius δ: every
 * corner has n·F > δ|n| by more than its error. F over the box lies in the convex hull of its corners, so then
 * |F| > δ throughout. This catches what the axis-aligned test above cannot: a long thin hull that runs past the
 * ball diagonally (nearly parallel edges, a vertex sliding along a face). The exact corner values differ from the
 * computed ones by at most `error` per axis, which moves n·F by at most |n|·error; the dot product itself errs by
 * at most 3.01 u |n|·|F| (we use 4 u), plus half a subnormal per product that underflows. What remains, the
 * rounding of |n| and of the comparison (a few u of the values compared), is covered by
 * CCD_SEPARATION_RELATIVE_SLACK. */
#define CCD_SEPARATION_RELATIVE_SLACK 0x1p-40
static inline int ccd_separated_along(const ccd_inclusion* s, const ccd_v3* F, int count, ccd_v3 n) {
  const double length = ccd_norm_above(n);
  if (!(length > 0)) return 0;
  const ccd_v3 magnitude = ccd_cwise_abs(n);
  const double carried = ccd_dot(magnitude, s->error) + 4 * CCD_DENORM_MIN;
  const double reach = s->thickness * length;
  for (int i = 0; i < count; ++i) {
    const double g = ccd_dot(n, F[i]);
    const double bound =
        carried + 4 * CCD_UNIT_ROUNDOFF * ccd_dot(magnitude, ccd_cwise_abs(F[i])) + CCD_SEPARATION_RELATIVE_SLACK * (fabs(g) + reach);
    if (!(g - bound > reach)) return 0;
  }
  return 1;
}

/* The point of a (u, v) box where |S + uX + vY| is least (a convex quadratic: the unconstrained minimum when it
 * lies in the box, else the least of the four edges' clamped minima). */
static inline void ccd_box_closest(ccd_v3 S, ccd_v3 X, ccd_v3 Y, double u0, double u1, double v0, double v1, double* u, double* v) {
  const double xx = ccd_dot(X, X), xy = ccd_dot(X, Y), yy = ccd_dot(Y, Y), sx = ccd_dot(S, X), sy = ccd_dot(S, Y);
  const double determinant = xx * yy - xy * xy;
  if (determinant > 0) {
    *u = (xy * sy - yy * sx) / determinant;
    *v = (xy * sx - xx * sy) / determinant;
    if (*u >= u0 && *u <= u1 && *v >= v0 && *v <= v1) return;
  }
  double best = INFINITY;
  for (int edge = 0; edge < 4; ++edge) {
    double eu, ev;
    if (edge < 2) { /* u fixed, v free */
      eu = edge ? u1 : u0;
      ev = yy > 0 ? ccd_clamp(-(sy + eu * xy) / yy, v0, v1) : v0;
    } else { /* v fixed, u free */
      ev = edge == 3 ? v1 : v0;
      eu = xx > 0 ? ccd_clamp(-(sx + ev * xy) / xx, u0, u1) : u0;
    }
    const double squared = ccd_squared_norm(ccd_f_value(S, eu, X, ev, Y));
    if (!(squared >= best)) {
      best = squared;
      *u = eu;
      *v = ev;
    }
  }
}

/* The point of the box's (u, v) range (its part inside the triangle for VF) where |F| at time t is least, in
 * *u, *v; returns F there. */
static inline ccd_v3 ccd_nearest_point_at(const ccd_inclusion* s, const ccd_sub_box* box, double t, double* nearest_u, double* nearest_v) {
  ccd_v3 S, X, Y;
  ccd_terms_at(s, t, &S, &X, &Y);
  double u = box->u0, v = box->v0;
  ccd_box_closest(S, X, Y, box->u0, box->u1, box->v0, box->v1, &u, &v);
  if (s->vertex_face && u + v > 1) {
    /* The box's nearest point is past the hypotenuse: the triangle's part's nearest point is on it (convexity). */
    const ccd_v3 base = ccd_add(S, Y), along = ccd_sub(X, Y);
    const double length2 = ccd_squared_norm(along);
    const double lo = ccd_max(box->u0, 1 - box->v1), hi = ccd_min(box->u1, 1 - box->v0);
    u = length2 > 0 ? ccd_clamp(-ccd_dot(base, along) / length2, lo, hi) : lo;
    v = 1 - u;
  }
  *nearest_u = u;
  *nearest_v = v;
  return ccd_f_value(S, u, X, v, Y);
}
/* F at the box's middle time and the point of its (u, v) range nearest 0 there: the plane normal to it supports
 * the box's values at that time exactly (the nearest point of a convex set), so ccd_separated_along then bounds the
 * distance over the whole (u, v) range, losing only F's change over the box's time. Only a direction: any n is
 * sound in ccd_separated_along. */
static inline ccd_v3 ccd_nearest_value(const ccd_inclusion* s, const ccd_sub_box* box) {
  double u, v;
  return ccd_nearest_point_at(s, box, box->t0 + (box->t1 - box->t0) / 2, &u, &v);
}

/* Excluded (no contact in the box), accepted (every point within δ + tolerance and the box at most toi_tolerance
 * long in time, or too small to split; *achieved is set), or split into *low and *high (in time when only the
 * box's length in time keeps it from being accepted). */
static inline int ccd_examine(ccd_inclusion* s, const ccd_sub_box* box, ccd_sub_box* low, ccd_sub_box* high, double* achieved) {
  if (s->vertex_face && box->u0 + box->v0 > 1) return CCD_EXCLUDED; /* exact: 1 is representable */
  ccd_v3 F[8];
  ccd_corners(s, box, F);
  /* The corners serve the split below; a VF box across the hypotenuse is tested on its triangle part. */
  ccd_v3 clipped[2 * CCD_CLIPPED_VERTICES];
  const ccd_v3* values = F;
  int count = 8;
  if (ccd_clips(s, box)) {
    count = ccd_clipped_values(s, box, clipped);
    values = clipped;
  }
  ccd_v3 f_min = values[0], f_max = values[0];
  for (int i = 0; i < count; ++i) {
    f_min = ccd_cwise_min(f_min, values[i]);
    f_max = ccd_cwise_max(f_max, values[i]);
  }
  const ccd_v3 middle_value = ccd_scale(0.5, ccd_add(f_min, f_max));
  f_min = ccd_sub(f_min, s->error);
  f_max = ccd_add(f_max, s->error);
  /* Nearest and farthest points of the widened corner box from 0, axis by axis. */
  double nearest2 = 0, farthest2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double gap = ccd_max(ccd_max(f_min.c[k], -f_max.c[k]), 0.0);
    nearest2 += gap * gap;
    const double far = ccd_max(fabs(f_min.c[k]), fabs(f_max.c[k]));
    farthest2 += far * far;
  }
  if (nearest2 > s->exclusion_bound) return CCD_EXCLUDED;
  if (ccd_separated_along(s, values, count, middle_value)) return CCD_EXCLUDED;
  if (ccd_separated_along(s, values, count, ccd_nearest_value(s, box))) return CCD_EXCLUDED;
  /* Split where F changes most (the largest corner difference along a parameter), among the parameters whose
   * interval still halves into two smaller doubles. */
  double change[3] = {0, 0, 0};
  for (int corner = 0; corner < 8; ++corner) {
    for (int dimension = 0; dimension < 3; ++dimension) {
      const int bit = 4 >> dimension;
      if (corner & bit) change[dimension] = ccd_max(change[dimension], ccd_max_coeff(ccd_cwise_abs(ccd_sub(F[corner], F[corner ^ bit]))));
    }
  }
  int d = -1;
  for (int dimension = 0; dimension < 3; ++dimension) {
    const double lo = ccd_box_bound(box, dimension, 0), hi = ccd_box_bound(box, dimension, 1);
    const double middle = lo + (hi - lo) / 2;
    const int splittable = lo < middle && middle < hi;
    if (splittable && (d < 0 || change[dimension] > change[d])) d = dimension;
  }
  const double reach = s->thickness + s->tolerance;
  const double t_middle = box->t0 + (box->t1 - box->t0) / 2;
  const int t_splittable = box->t0 < t_middle && t_middle < box->t1;
  const int within_reach = farthest2 <= reach * reach;
  if ((within_reach && (box->t1 - box->t0 <= s->toi_tolerance || !t_splittable)) || d < 0) {
    *achieved = ccd_max(0.0, sqrt(farthest2) - s->thickness);
    return CCD_ACCEPTED;
  }
  /* Time first while the box is longer than toi_tolerance: the test along the nearest value bounds the distance
   * over the whole (u, v) range, so the search advances in time instead of cutting (u, v) ever finer at one t0
   * (near a first touch at δ > 0 every box that reaches past the contact holds a piece of it, at any size). */
  if (t_splittable && box->t1 - box->t0 > s->toi_tolerance) d = 0;
  *low = *box;
  *high = *box;
  const double lo = ccd_box_bound(box, d, 0), hi = ccd_box_bound(box, d, 1);
  const double middle = lo + (hi - lo) / 2;
  ccd_set_box_bound(low, d, 1, middle);
  ccd_set_box_bound(high, d, 0, middle);
  low->order = s->created++;
  high->order = s->created++;
  return CCD_SPLIT;
}

static inline int ccd_in_domain(const ccd_inclusion* s, double u, double v) {
  return u >= 0 && v >= 0 && (s->vertex_face ? u + v <= 1 : u <= 1 && v <= 1);
}

/* A domain point within δ (with room) proves a contact at t: returns 1. Clamps (u, v) into the domain first. */
static inline int ccd_point_within_thickness(const ccd_inclusion* s, double t, double u, double v) {
  u = ccd_clamp(u, 0.0, 1.0);
  v = ccd_clamp(v, 0.0, 1.0);
  if (s->vertex_face && u + v > 1) {
    const double excess = (u + v - 1) / 2;
    u = ccd_max(0.0, u - excess);
    v = ccd_max(0.0, 1 - u);
  }
  if (!ccd_in_domain(s, u, v)) return 0;
  ccd_v3 S, X, Y;
  ccd_terms_at(s, t, &S, &X, &Y);
  const double distance = ccd_norm(ccd_f_value(S, u, X, v, Y)) + ccd_norm(s->error);
  return distance * (1 + CCD_PROOF_RELATIVE_SLACK) <= s->thickness;
}

/* Whether the pair is proven within δ at time t, at the domain's point nearest 0 there (ccd_nearest_point_at, for
 * the whole domain): the distance there is computed with F's error bound (ccd_point_within_thickness). */
static inline int ccd_within_thickness_at(const ccd_inclusion* s, double t) {
  const ccd_sub_box domain = ccd_sub_box_make(t, t, 0, 1, 0, 1, 0);
  double u, v;
  ccd_nearest_point_at(s, &domain, t, &u, &v);
  return isfinite(u) && isfinite(v) && ccd_point_within_thickness(s, t, u, v);
}

/* 3×3 matrices, row-major m[row][column]. */
typedef struct {
  double m[3][3];
} ccd_m3;

static inline ccd_m3 ccd_m3_columns(ccd_v3 a, ccd_v3 b, ccd_v3 c) {
  ccd_m3 r;
  for (int i = 0; i < 3; ++i) {
    r.m[i][0] = a.c[i];
    r.m[i][1] = b.c[i];
    r.m[i][2] = c.c[i];
  }
  return r;
}
static inline double ccd_m3_determinant(const ccd_m3* a) {
  const double(*m)[3] = a->m;
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}
static inline double ccd_m3_cofactor(const ccd_m3* a, int i, int j) {
  const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
  return a->m[i1][j1] * a->m[i2][j2] - a->m[i1][j2] * a->m[i2][j1];
}
/* The inverse by cofactors, in the order of Eigen's 3×3 inverse. */
static inline ccd_m3 ccd_m3_inverse(const ccd_m3* a) {
  const double c0 = ccd_m3_cofactor(a, 0, 0), c1 = ccd_m3_cofactor(a, 1, 0), c2 = ccd_m3_cofactor(a, 2, 0);
  const double determinant = (c0 * a->m[0][0] + c1 * a->m[1][0]) + c2 * a->m[2][0];
  const double inverse_determinant = 1.0 / determinant;
  ccd_m3 r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r.m[i][j] = ccd_m3_cofactor(a, j, i) * inverse_determinant;
  }
  r.m[0][0] = c0 * inverse_determinant;
  r.m[0][1] = c1 * inverse_determinant;
  r.m[0][2] = c2 * inverse_determinant;
  return r;
}
/* A·x in the order the former Eigen product summed it (rows 0 and 1 as one SIMD pair, left to right; row 2 as
 * the scalar remainder, right to left). */
static inline ccd_v3 ccd_m3_apply(const ccd_m3* a, ccd_v3 x) {
  ccd_v3 r;
  for (int i = 0; i < 2; ++i) r.c[i] = (a->m[i][0] * x.c[0] + a->m[i][1] * x.c[1]) + a->m[i][2] * x.c[2];
  r.c[2] = a->m[2][0] * x.c[0] + (a->m[2][1] * x.c[1] + a->m[2][2] * x.c[2]);
  return r;
}
/* Row i of A dotted with x, summed right to left (Eigen's order for a strided row). */
static inline double ccd_m3_row_dot(const ccd_m3* a, int i, ccd_v3 x) { return a->m[i][0] * x.c[0] + (a->m[i][1] * x.c[1] + a->m[i][2] * x.c[2]); }

/* Miranda's theorem in a small box around (t, u, v): returns 1 and the box's t1 in *toi when it proves a zero (the
 * zero, and so the earliest contact, is no later than that). */
static inline int ccd_miranda(const ccd_inclusion* s, double t, double u, double v, ccd_v3 dS, ccd_v3 dX, ccd_v3 dY, double* toi) {
  const double w = CCD_MIRANDA_HALF_WIDTH;
  const ccd_sub_box box = ccd_sub_box_make(t - w, t + w, u - w, u + w, v - w, v + w, 0);
  if (box.t0 < 0 || box.t1 > 1 || !ccd_in_domain(s, box.u0, box.v0) || !ccd_in_domain(s, box.u1, box.v1) || !ccd_in_domain(s, box.u0, box.v1) ||
      !ccd_in_domain(s, box.u1, box.v0)) {
    return 0;
  }
  ccd_v3 S, X, Y;
  ccd_terms_at(s, t, &S, &X, &Y);
  const ccd_m3 jacobian = ccd_m3_columns(ccd_f_value(dS, u, dX, v, dY), X, Y);
  if (!(fabs(ccd_m3_determinant(&jacobian)) > 0)) return 0;
  const ccd_m3 A = ccd_m3_inverse(&jacobian);
  ccd_m3 magnitude;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) magnitude.m[i][j] = fabs(A.m[i][j]);
  }
  ccd_v3 F[8];
  ccd_corners(s, &box, F);
  for (int i = 0; i < 3; ++i) {
    const int bit = 4 >> i;
    int low_negative = 1, low_positive = 1, high_negative = 1, high_positive = 1;
    for (int corner = 0; corner < 8; ++corner) {
      const double g = ccd_m3_row_dot(&A, i, F[corner]);
      /* |A·F_computed - A·F_exact| <= |A|·error, plus the rounding of the 3-term product (< 4u|A||F|). */
      const double bound = ccd_m3_row_dot(&magnitude, i, s->error) + 4 * CCD_UNIT_ROUNDOFF * ccd_m3_row_dot(&magnitude, i, ccd_cwise_abs(F[corner]));
      const int negative = g + bound<0, positive = g - bound> 0;
      if (corner & bit) {
        high_negative = high_negative && negative;
        high_positive = high_positive && positive;
      } else {
        low_negative = low_negative && negative;
        low_positive = low_positive && positive;
      }
    }
    if (!((low_negative && high_positive) || (low_positive && high_negative))) return 0;
  }
  *toi = box.t1;
  return 1;
}

/* Stage 3: a time by which a contact is proven cheaply (returns 1 and *earliest), or 0. Starting from the given
 * times (the windows', earliest first; stage 2), Newton steps locate a zero of F; Miranda's theorem then proves one
 * in a small box around it: with A the inverse Jacobian there, each component G_i of G = A·F is <= 0 on one face of
 * the box across parameter i and >= 0 on the opposite face. G is trilinear, so its extremes on a face are at the
 * face's corners, which are box corners. For δ > 0 a domain point with |F| <= δ proves a contact by itself. The
 * first seed that proves one ends the stage. A mistake here could only add a false alarm (a search stopped early
 * reports collides, at a TOI still no later than any contact): answers "no" come from exclusions alone. */
static inline int ccd_certify(const ccd_inclusion* s, const double* times, int count, double* earliest) {
  ccd_v3 dS, dX, dY;
  ccd_split_terms(s, s->dx, &dS, &dX, &dY);
  int found = 0;
  for (int i = 0; i < count && !found; ++i) {
    double t = times[i];
    ccd_v3 S, X, Y;
    ccd_terms_at(s, t, &S, &X, &Y);
    const double xx = ccd_dot(X, X), xy = ccd_dot(X, Y), yy = ccd_dot(Y, Y);
    const double normal_determinant = xx * yy - xy * xy;
    if (!(fabs(normal_determinant) > 0)) continue;
    const double inverse_determinant = 1.0 / normal_determinant;
    const double b0 = -ccd_dot(X, S), b1 = -ccd_dot(Y, S);
    double u = (yy * inverse_determinant) * b0 + (-xy * inverse_determinant) * b1;
    double v = (-xy * inverse_determinant) * b0 + (xx * inverse_determinant) * b1;
    /* Resting contacts within δ have no zero of F: try the closest domain point at the candidate time first. */
    if (s->thickness > 0 && ccd_within_thickness_at(s, t)) {
      if (!found || t < *earliest) *earliest = t;
      found = 1;
      continue;
    }
    for (int newton = 0; newton < 3; ++newton) {
      ccd_terms_at(s, t, &S, &X, &Y);
      const ccd_m3 jacobian = ccd_m3_columns(ccd_f_value(dS, u, dX, v, dY), X, Y);
      if (!(fabs(ccd_m3_determinant(&jacobian)) > 0)) break;
      const ccd_m3 inverse = ccd_m3_inverse(&jacobian);
      const ccd_v3 step = ccd_m3_apply(&inverse, ccd_f_value(S, u, X, v, Y));
      t -= step.c[0];
      u -= step.c[1];
      v -= step.c[2];
    }
    if (!(t >= 0 && t <= 1) || !isfinite(u) || !isfinite(v)) continue;
    double proven = 0;
    int is_proven = 0;
    if (s->thickness > 0 && ccd_point_within_thickness(s, t, u, v)) {
      proven = t;
      is_proven = 1;
    }
    if (!is_proven) is_proven = ccd_miranda(s, t, u, v, dS, dX, dY, &proven);
    if (is_proven && (!found || proven < *earliest)) {
      *earliest = proven;
      found = 1;
    }
  }
  return found;
}

/* What a conservative test answers. overflow: the caller's sub-box storage was too small, or the search gave up
 * after give_up_after iterations; nothing else is set, and the caller reruns the test with more room and no limit
 * (the search is deterministic, so a rerun gives the answer it would have). */
typedef struct {
  int collides;
  double toi;
  int hit_iteration_cap;
  double achieved_tolerance;
  int overflow;
} ccd_conservative_outcome;

static inline ccd_conservative_outcome ccd_outcome_make(int collides, double toi, double achieved_tolerance) {
  ccd_conservative_outcome outcome;
  outcome.collides = collides;
  outcome.toi = toi;
  outcome.hit_iteration_cap = 0;
  outcome.achieved_tolerance = achieved_tolerance;
  outcome.overflow = 0;
  return outcome;
}

/* ---- Stage 2: the time windows, where a contact is possible at all. ----
 * The pair can only touch at a time t when the distance from S to the plane (VF) or line (EE) spanned by X and Y
 * is at most δ: |V(t)| <= δ |X(t) × Y(t)|, with V = S·(X × Y) the coplanarity cubic (geometry.h) and the bound on
 * its right side at most thr = δ |X|max |Y|max (|X(t)| is convex in t, so its largest value on the step is at an
 * end). V is a trilinear function of three vectors that are each linear in t, so its Bernstein coefficients on
 * [0, 1] are the blossom's values, the triple products of the ends:
 *   b0 = V(X0, Y0, S0), b1 = (V(X1, Y0, S0) + V(X0, Y1, S0) + V(X0, Y0, S1)) / 3, b2 = the same with two ends at 1,
 *   b3 = V(X1, Y1, S1),
 * and on any interval the cubic lies between the smallest and the largest of its coefficients there (de Casteljau
 * halves an interval). Intervals whose coefficients all lie above thr or below -thr (by more than their error) hold
 * no contact; intervals whose coefficients all lie inside the band are kept whole; the rest are halved. What
 * remains, merged where adjacent, are the windows: the search that follows (stage 4) never looks outside them.
 * At δ = 0 the band is V = 0 and a transversal contact's window is the root of V to about 1e-12 of the step.
 *
 * Error bound (u = 2^-53, the rows rescaled so that every coordinate is below 1; nothing here is
 * used to answer "yes", only to drop time where the answer is "no"). S, X, Y at t = 0 and 1 are one rounded
 * difference of two rows each: relative error u per component, which moves a triple product by at most
 * ((1 + u)^3 - 1) P < 3.01 u P, P = |S|·(|X| × |Y|) taken with absolute values (the product's "permanent").
 * Computing a triple product (a cross product, then a dot) errs by at most γ5 P < 5.01 u P; b1 and b2 add two
 * sums and a division by 3 (3 u of at most 3 Pmax / 3): each coefficient errs by less than 12 u Pmax, Pmax the
 * largest P of the eight end combinations. We use CCD_WINDOW_ERROR_UNITS u Pmax (computed Pmax is within 6 u of
 * the true one), plus CCD_WINDOW_ERROR_SLACK_UNITS u of the largest coefficient for the rounding of the band
 * comparisons, plus subnormals for products that underflow. Each halving computes every new coefficient by at
 * most three averages of two coefficients (halving is exact; the sum rounds by at most u of twice the largest
 * magnitude), so a level adds 3 u Cmax and 3 half-subnormals; we add 4 of each. A child's coefficients are
 * convex combinations of its parent's, so inherited errors do not grow. */
/* of u·Pmax, covering the 12 derived above */
#define CCD_WINDOW_ERROR_UNITS 32.0
/* of u·Cmax, covering the rounding of `lowest - error` and `highest + error` in the band test */
#define CCD_WINDOW_ERROR_SLACK_UNITS 4.0
/* of u·Cmax and of the smallest subnormal, added per halving (3 derived above) */
#define CCD_WINDOW_HALVING_UNITS 4.0
/* The band's own bound δ |X|max |Y|max, rounded up: its three roundings and the u per component of X and Y are
 * below 10 u, which this covers with room. */
#define CCD_WINDOW_BAND_RELATIVE_SLACK 0x1p-40
/* Halvings before an interval is kept whole: 2^-40 of the step (about 1e-12), below which a transversal root's
 * window cannot shrink anyway (the coefficients' error, over the cubic's slope). */
#define CCD_WINDOW_DEPTH 40
/* Halvings in all, then every interval left is kept whole: three simple roots need about 3 × 45. */
#define CCD_WINDOW_HALVINGS 192
/* Windows kept; an extra one is merged into the last (a superset: still sound). */
#define CCD_MAX_WINDOWS 8

typedef struct {
  double t0, t1;
} ccd_window;

typedef struct {
  double t0, t1, c[4], error;
  int depth;
} ccd_band_node;

/* A cubic in Bernstein form on its interval, at local parameter x in [0, 1] (de Casteljau), and its slope there. */
static inline double ccd_bernstein_value(const double c[4], double x) {
  const double y = 1 - x;
  const double a01 = y * c[0] + x * c[1], a12 = y * c[1] + x * c[2], a23 = y * c[2] + x * c[3];
  return y * (y * a01 + x * a12) + x * (y * a12 + x * a23);
}
static inline double ccd_bernstein_slope(const double c[4], double x) {
  const double y = 1 - x, d0 = c[1] - c[0], d1 = c[2] - c[1], d2 = c[3] - c[2];
  return 3 * (y * (y * d0 + x * d1) + x * (y * d1 + x * d2));
}
/* Where the increasing cubic sign·c reaches `level` on [0, 1], to within `close` of the value (a guess, not a
 * bound: regula falsi's first point, then Newton steps kept inside a shrinking bracket, a bisection step whenever
 * Newton leaves it). */
static inline double ccd_bernstein_crossing(const double c[4], double sign, double level, double close) {
  const double first = sign * c[0] - level, last = sign * c[3] - level;
  double lo = 0, hi = 1, x = first < 0 && last > 0 ? first / (first - last) : 0.5;
  for (int i = 0; i < 16; ++i) {
    const double value = sign * ccd_bernstein_value(c, x) - level;
    if (fabs(value) <= close) break;
    if (value < 0)
      lo = x;
    else
      hi = x;
    const double slope = sign * ccd_bernstein_slope(c, x);
    double next = slope > 0 ? x - value / slope : (lo + hi) / 2;
    if (!(next > lo && next < hi)) next = (lo + hi) / 2;
    if (next == x) break;
    x = next;
  }
  return x;
}

static inline double ccd_triple(ccd_v3 s, ccd_v3 x, ccd_v3 y) { return ccd_dot(s, ccd_cross(x, y)); }
static inline double ccd_triple_magnitude(ccd_v3 s, ccd_v3 x, ccd_v3 y) {
  return ccd_dot(ccd_cwise_abs(s), ccd_v3_make(fabs(x.c[1] * y.c[2]) + fabs(x.c[2] * y.c[1]), fabs(x.c[2] * y.c[0]) + fabs(x.c[0] * y.c[2]),
                                               fabs(x.c[0] * y.c[1]) + fabs(x.c[1] * y.c[0])));
}

static inline void ccd_add_window(ccd_window* windows, int* count, double t0, double t1) {
  if (*count > 0 && windows[*count - 1].t1 >= t0) {
    windows[*count - 1].t1 = ccd_max(windows[*count - 1].t1, t1);
  } else if (*count < CCD_MAX_WINDOWS) {
    windows[*count].t0 = t0;
    windows[*count].t1 = t1;
    ++*count;
  } else {
    windows[*count - 1].t1 = t1;
  }
}

/* On an interval where the cubic is certainly monotone (every difference of consecutive coefficients, the slope's
 * own Bernstein coefficients, has one sign beyond twice the coefficients' error), it meets the band in one
 * interval, whose ends are guessed by Newton steps and then proven: a point x short of the lower end where the
 * value is below -band by more than its error bounds the window from below (the cubic only rises), and likewise a
 * point past the upper end. x is taken on a grid of 2^-(52 - depth) of the interval, so that the time it stands
 * for, t0 + x (t1 - t0), is computed exactly (t0 is a multiple of the interval's length, a power of two). The value
 * there errs by the coefficients' error plus the rounding of de Casteljau's three levels (each a (1 - x) a + x b:
 * at most 4 u of the largest coefficient; CCD_WINDOW_EVALUATION_UNITS covers the 12). Adds the window and returns 1
 * when both ends are proven; returns 0 (nothing added) otherwise, and the interval is halved as before. */
#define CCD_WINDOW_EVALUATION_UNITS 16.0
static inline int ccd_monotone_window(const ccd_band_node* node, double band, double largest, ccd_window* windows, int* count) {
  double smallest_rise = INFINITY, sign = 0;
  for (int i = 0; i < 3; ++i) {
    const double d = node->c[i + 1] - node->c[i];
    const double direction = d > 0 ? 1.0 : -1.0;
    if (i == 0) sign = direction;
    if (direction != sign || !(fabs(d) > 2 * node->error)) return 0;
    smallest_rise = ccd_min(smallest_rise, fabs(d) - 2 * node->error);
  }
  const double error = node->error + CCD_WINDOW_EVALUATION_UNITS * CCD_UNIT_ROUNDOFF * largest + 8 * CCD_DENORM_MIN;
  /* The slope is at least 3·smallest_rise per unit of x: a step of `margin` clears twice the value's error. */
  const double margin = 4 * error / (3 * smallest_rise);
  const double grid = ldexp(1.0, 52 - node->depth), length = node->t1 - node->t0;
  double start = node->t0, end = node->t1;
  if (sign * node->c[0] < -band) {
    double x = ccd_bernstein_crossing(node->c, sign, -band, error) - margin;
    x = floor(x * grid) / grid;
    if (x > 0) {
      if (!(sign * ccd_bernstein_value(node->c, x) + error < -band)) return 0;
      start = node->t0 + x * length;
    }
  }
  if (sign * node->c[3] > band) {
    double x = ccd_bernstein_crossing(node->c, sign, band, error) + margin;
    x = ceil(x * grid) / grid;
    if (x < 1) {
      if (!(sign * ccd_bernstein_value(node->c, x) - error > band)) return 0;
      end = node->t0 + x * length;
    }
  }
  if (!(start <= end)) return 0;
  ccd_add_window(windows, count, start, end);
  return 1;
}

/* The windows, earliest first (at most CCD_MAX_WINDOWS); returns their count, 0 when the pair cannot touch. */
static inline int ccd_time_windows(const ccd_inclusion* s, ccd_window windows[CCD_MAX_WINDOWS]) {
  ccd_v3 S[2], X[2], Y[2];
  ccd_split_terms(s, s->x0, &S[0], &X[0], &Y[0]);
  ccd_split_terms(s, s->x1, &S[1], &X[1], &Y[1]);
  double blossom[8], magnitude = 0; /* index = s·4 + x·2 + y: which end each argument is taken at */
  for (int i = 0; i < 8; ++i) {
    const ccd_v3 si = S[i >> 2], xi = X[(i >> 1) & 1], yi = Y[i & 1];
    blossom[i] = ccd_triple(si, xi, yi);
    magnitude = ccd_max(magnitude, ccd_triple_magnitude(si, xi, yi));
  }
  ccd_band_node stack[CCD_WINDOW_DEPTH + 2];
  int size = 1;
  stack[0].t0 = 0;
  stack[0].t1 = 1;
  stack[0].c[0] = blossom[0];
  stack[0].c[1] = (blossom[4] + blossom[2] + blossom[1]) / 3;
  stack[0].c[2] = (blossom[6] + blossom[5] + blossom[3]) / 3;
  stack[0].c[3] = blossom[7];
  double largest = 0;
  for (int i = 0; i < 4; ++i) largest = ccd_max(largest, fabs(stack[0].c[i]));
  stack[0].error =
      CCD_WINDOW_ERROR_UNITS * CCD_UNIT_ROUNDOFF * magnitude + CCD_WINDOW_ERROR_SLACK_UNITS * CCD_UNIT_ROUNDOFF * largest + 64 * CCD_DENORM_MIN;
  stack[0].depth = 0;
  const double step_error = CCD_WINDOW_HALVING_UNITS * (CCD_UNIT_ROUNDOFF * (largest + stack[0].error) + CCD_DENORM_MIN);
  const double x_most = ccd_norm_above(ccd_cwise_max(ccd_cwise_abs(X[0]), ccd_cwise_abs(X[1])));
  const double y_most = ccd_norm_above(ccd_cwise_max(ccd_cwise_abs(Y[0]), ccd_cwise_abs(Y[1])));
  const double band = s->thickness > 0 ? s->thickness * x_most * y_most * (1 + CCD_WINDOW_BAND_RELATIVE_SLACK) + 4 * CCD_DENORM_MIN : 0.0;
  int count = 0, halvings = 0;
  while (size > 0) {
    const ccd_band_node node = stack[--size];
    double lowest = node.c[0], highest = node.c[0];
    for (int i = 1; i < 4; ++i) {
      lowest = ccd_min(lowest, node.c[i]);
      highest = ccd_max(highest, node.c[i]);
    }
    if (lowest - node.error > band || highest + node.error < -band) continue; /* outside the band throughout */
    const int inside = highest + node.error <= band && lowest - node.error >= -band;
    if (!inside && ccd_monotone_window(&node, band, ccd_max(fabs(lowest), fabs(highest)), windows, &count)) continue;
    const double middle = node.t0 + (node.t1 - node.t0) / 2;
    if (inside || node.depth >= CCD_WINDOW_DEPTH || halvings >= CCD_WINDOW_HALVINGS || !(node.t0 < middle && middle < node.t1)) {
      ccd_add_window(windows, &count, node.t0, node.t1);
      continue;
    }
    ++halvings;
    /* de Casteljau at the middle */
    const double a01 = (node.c[0] + node.c[1]) / 2, a12 = (node.c[1] + node.c[2]) / 2, a23 = (node.c[2] + node.c[3]) / 2;
    const double b012 = (a01 + a12) / 2, b123 = (a12 + a23) / 2, m = (b012 + b123) / 2;
    ccd_band_node left = node, right = node;
    left.t1 = middle;
    right.t0 = middle;
    left.c[1] = a01;
    left.c[2] = b012;
    left.c[3] = m;
    right.c[0] = m;
    right.c[1] = b123;
    right.c[2] = a23;
    left.error = right.error = node.error + step_error;
    left.depth = right.depth = node.depth + 1;
    stack[size++] = right;
    stack[size++] = left;
  }
  return count;
}

/* ---- Stage 4: the search, within the windows. ----
 * Sub-boxes are examined earliest first (a heap ordered by t0), so when a box is taken every part of the domain
 * that starts earlier has been excluded: its t0 is a lower bound of the earliest contact, and so is the t0 of the
 * box on top. The search ends
 *   - when every box is excluded: no contact (with stages 1 and 2, the only ways this test answers "no");
 *   - when a box is accepted (every point of it within δ + tolerance, and at most toi_tolerance long in time): the
 *     pair collides, or comes within the distance tolerance of it, at its t0;
 *   - when the top box starts no earlier than `upper - toi_tolerance`, upper being a time by which a contact is
 *     proven (stage 3): the earliest contact lies between the top's t0 and upper, at most toi_tolerance apart;
 *   - when the iteration cap is hit: "collides" with the top's t0 (a lower bound), flagged.
 * Every TOI reported is thus a t0 no later than the earliest contact; for a contact proven by stage 3 or by a
 * point within δ at a box's end (below), no earlier than it by more than toi_tolerance. A box accepted on the
 * distance tolerance may come before the contact by the time the pair takes to close that distance: that is what
 * the tolerance means (and what a false alarm's TOI is: the earliest time the pair may be that close). */
/* A shortcut to acceptance for a box already short in time (the search would otherwise halve u and v some 30
 * times each down to the contact): the box of the same times around the domain's nearest point at its middle
 * time, small enough in u and v that their share of its extent is a quarter of the distance tolerance, is examined
 * as any box is. Accepted, it holds a point within δ + tolerance throughout, and the outer box's t0 is the TOI the
 * search would report (the outer box is on top: nothing earlier is left). Returns 1 (and *achieved) then. */
static inline int ccd_accept_nearest(ccd_inclusion* s, const ccd_sub_box* box, double* achieved) {
  double u, v;
  const ccd_v3 nearest = ccd_nearest_point_at(s, box, box->t0 + (box->t1 - box->t0) / 2, &u, &v);
  if (!(ccd_norm(nearest) <= s->thickness + s->tolerance / 2)) return 0;
  ccd_v3 S, X, Y;
  ccd_terms_at(s, box->t0, &S, &X, &Y);
  const double spread = ccd_norm(X) + ccd_norm(Y);
  if (!(spread > 0)) return 0;
  const double h = s->tolerance / (4 * spread);
  ccd_sub_box tiny =
      ccd_sub_box_make(box->t0, box->t1, ccd_max(box->u0, u - h), ccd_min(box->u1, u + h), ccd_max(box->v0, v - h), ccd_min(box->v1, v + h), 0);
  ccd_sub_box low, high;
  return ccd_examine(s, &tiny, &low, &high, achieved) == CCD_ACCEPTED;
}

/* Certified advancement through a window's start (before stage 3 and the search): along n, F's value at the
 * nearest point of the domain at the window's current start t, the gap n·F at each vertex of the domain (the (u, v)
 * square's corners, the triangle's for VF) is linear in time, so the time at which the first of them would come
 * within δ|n| is one division each. The box from t to a little short of that time is then tested as any box is
 * (ccd_examine's own test along n, with its error bound, on the box's values): when it is separated, the window
 * starts at its end, and again from there. Near a first touch the nearest direction is the separating one, so each
 * step closes most of what is left, as conservative advancement does, but every step is proven. Returns 0 when the
 * whole window is passed (no contact in it), 1 otherwise (window->t0 moved forward, or not). */
#define CCD_ADVANCE_STEPS 24
/* Of the way to the first vertex's crossing each step goes: short of it, so that the proof at the box's end holds. */
#define CCD_ADVANCE_FRACTION 0.9
static inline int ccd_advance(ccd_inclusion* s, ccd_window* window) {
  const int vertices = s->vertex_face ? 3 : 4;
  const double cu[4] = {0, 1, 0, 1}, cv[4] = {0, 0, 1, 1};
  for (int step = 0; step < CCD_ADVANCE_STEPS; ++step) {
    const double t = window->t0;
    ccd_sub_box box = ccd_sub_box_make(t, window->t1, 0, 1, 0, 1, 0);
    double nearest_u, nearest_v;
    const ccd_v3 n = ccd_nearest_point_at(s, &box, t, &nearest_u, &nearest_v);
    const double length = ccd_norm(n);
    if (!(length > 0)) return 1;
    ccd_v3 S0, X0, Y0, S1, X1, Y1;
    ccd_terms_at(s, t, &S0, &X0, &Y0);
    ccd_terms_at(s, window->t1, &S1, &X1, &Y1);
    const double reach = s->thickness * length;
    double end = window->t1;
    for (int i = 0; i < vertices; ++i) {
      const double start_gap = ccd_dot(n, ccd_f_value(S0, cu[i], X0, cv[i], Y0)) - reach;
      const double end_gap = ccd_dot(n, ccd_f_value(S1, cu[i], X1, cv[i], Y1)) - reach;
      if (!(start_gap > 0)) return 1; /* no room along n at t */
      if (end_gap < 0) end = ccd_min(end, t + (window->t1 - t) * (start_gap / (start_gap - end_gap)));
    }
    if (end < window->t1) end = t + (end - t) * CCD_ADVANCE_FRACTION;
    if (!(end > t)) return 1;
    box.t1 = end;
    ccd_v3 values[2 * CCD_CLIPPED_VERTICES];
    const int count = ccd_box_values(s, &box, values);
    if (ccd_over_budget(s) || !ccd_separated_along(s, values, count, n)) return 1;
    if (end >= window->t1) return 0;
    window->t0 = end;
  }
  return 1;
}

static inline ccd_conservative_outcome ccd_window_search(ccd_inclusion* s, const ccd_window* windows, int count, double upper, ccd_sub_box* storage,
                                                         int capacity) {
  ccd_conservative_outcome result = ccd_outcome_make(0, NAN, 0);
  int size = 0;
  for (int i = 0; i < count; ++i) {
    if (size + 1 > capacity) {
      result.overflow = 1;
      return result;
    }
    ccd_heap_push(storage, &size, ccd_sub_box_make(windows[i].t0, windows[i].t1, 0, 1, 0, 1, s->created++));
  }
  while (size > 0) {
    if (storage[0].t0 >= upper - s->toi_tolerance) {
      result.collides = 1;
      result.toi = ccd_min(storage[0].t0, upper);
      return result;
    }
    if (ccd_over_budget(s)) break;
    const ccd_sub_box box = ccd_heap_pop(storage, &size);
    ccd_sub_box low, high;
    double achieved = 0;
    const int verdict = ccd_examine(s, &box, &low, &high, &achieved);
    if (verdict == CCD_EXCLUDED) continue;
    if (verdict == CCD_ACCEPTED || (box.t1 - box.t0 <= s->toi_tolerance && ccd_accept_nearest(s, &box, &achieved))) {
      result.collides = 1;
      result.toi = box.t0;
      result.achieved_tolerance = achieved;
      return result;
    }
    /* δ > 0: the earliest contact is a first touch of the δ-tube, where boxes are accepted only when tiny; a pair
     * proven within δ at a box's end bounds the contact by then instead. */
    if (s->thickness > 0 && box.t1 < upper && ccd_within_thickness_at(s, box.t1)) upper = box.t1;
    if (size + 2 > capacity) {
      result.overflow = 1;
      return result;
    }
    ccd_heap_push(storage, &size, low);
    ccd_heap_push(storage, &size, high);
  }
  if (s->gave_up) {
    result.overflow = 1;
    return result;
  }
  if (size == 0) return result; /* every box excluded: proven no contact */
  result.collides = 1;
  result.hit_iteration_cap = 1;
  result.achieved_tolerance = INFINITY;
  result.toi = ccd_min(storage[0].t0, upper);
  return result;
}

/* Stage 0, for δ > 0: a pair already within δ at t = 0 (resting contact) collides, and 0 is its TOI. The distance
 * is to a point of each closed primitive, so rounding can only move it by a few ulps of the coordinates;
 * CCD_START_DISTANCE_MARGIN of their squared size is far beyond that. At δ = 0 it never fires. */
static inline int ccd_within_thickness_at_start(const ccd_v3 r[8], double thickness, int vertex_face) {
  if (!(thickness > 0)) return 0;
  double scale = 0;
  for (int i = 0; i < 4; ++i) scale = ccd_max(scale, ccd_max_coeff(ccd_cwise_abs(r[i])));
  const double squared = ccd_pair_squared_distance(r, vertex_face);
  return squared <= thickness * thickness - CCD_START_DISTANCE_MARGIN * scale * scale;
}

/* The whole conservative test of one pair (the `conservative` narrow phase, inclusion.cpp): rescale; stage 0 (a pair
 * within δ at the start); stage 1 (the whole domain at once excludes far pairs); stage 2 (the time windows: most
 * pairs that come close without touching end here); stage 3 (a cheap proof of a contact, which bounds the TOI from
 * above); stage 4 (the search within the windows, which bounds it from below). `storage` holds `capacity`
 * sub-boxes; on overflow the caller retries with more. give_up_after > 0 ends a long search with an overflow (the
 * caller reruns it with 0). Runs in round-to-nearest (the caller's duty on the host; the only mode on an OpenCL
 * device). */
static inline ccd_conservative_outcome ccd_conservative_test(const ccd_v3 original[8], double thickness_given, int vertex_face,
                                                             double tolerance_fraction, double toi_tolerance, long max_iterations, long give_up_after,
                                                             ccd_sub_box* storage, int capacity) {
  ccd_conservative_outcome result = ccd_outcome_make(1, 0, INFINITY);
  ccd_v3 rows[8];
  for (int i = 0; i < 8; ++i) rows[i] = original[i];
  double thickness = thickness_given;
  int exponent = 0;
  if (!ccd_scale_to_unit(rows, &thickness, &exponent)) return result; /* unscalable: never a miss */
  result.achieved_tolerance = 0;
  if (ccd_within_thickness_at_start(rows, thickness, vertex_face)) return result;
  ccd_inclusion search;
  ccd_inclusion_init(&search, rows, thickness, vertex_face, tolerance_fraction, toi_tolerance, max_iterations);
  search.give_up_after = give_up_after;
  const ccd_sub_box root = ccd_sub_box_make(0, 1, 0, 1, 0, 1, 0);
  ccd_sub_box low, high;
  double achieved = 0;
  ccd_over_budget(&search);
  if (ccd_examine(&search, &root, &low, &high, &achieved) == CCD_EXCLUDED) return ccd_outcome_make(0, NAN, 0);
  ccd_window windows[CCD_MAX_WINDOWS];
  int count = ccd_time_windows(&search, windows);
  /* Certified advancement through each window's start; a window passed whole holds no contact. */
  int kept = 0;
  for (int i = 0; i < count; ++i) {
    /* (a window already within toi_tolerance has nothing to gain) */
    if (windows[i].t1 - windows[i].t0 <= toi_tolerance || ccd_advance(&search, &windows[i])) windows[kept++] = windows[i];
  }
  count = kept;
  if (search.gave_up) {
    result = ccd_outcome_make(0, NAN, 0);
    result.overflow = 1;
    return result;
  }
  if (count == 0) return ccd_outcome_make(0, NAN, 0);
  /* Newton's starting times: each window's middle, and its start too when it is long enough to matter; at δ > 0
   * also toi_tolerance past its start, where advancement has usually brought a first touch within reach. */
  double seeds[3 * CCD_MAX_WINDOWS];
  int seed_count = 0;
  for (int i = 0; i < count; ++i) {
    const double length = windows[i].t1 - windows[i].t0;
    if (length > CCD_MIRANDA_HALF_WIDTH) seeds[seed_count++] = windows[i].t0;
    if (thickness > 0 && toi_tolerance < length / 2) seeds[seed_count++] = windows[i].t0 + toi_tolerance;
    seeds[seed_count++] = windows[i].t0 + length / 2;
  }
  double upper = INFINITY;
  if (ccd_certify(&search, seeds, seed_count, &upper)) {
    if (upper <= 0) return result; /* a contact proven at t = 0 is the earliest there can be */
    /* The proven contact lies in a window too: no later than the last window time up to upper. */
    double latest = -1;
    for (int i = 0; i < count; ++i) {
      if (windows[i].t0 <= upper) latest = ccd_max(latest, ccd_min(windows[i].t1, upper));
    }
    if (latest >= 0) upper = latest;
  }
  result = ccd_window_search(&search, windows, count, upper, storage, capacity);
  if (!result.overflow) result.achieved_tolerance = ldexp(result.achieved_tolerance, exponent); /* the pair's units */
  return result;
}

#endif
