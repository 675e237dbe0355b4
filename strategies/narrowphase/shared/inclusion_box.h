/* The conservative narrow phase's search state and its test of one sub-box of (t, u, v): exclusion (the box's corner
 * hull misses the ball of radius δ), acceptance (the box is proven within δ, or small enough to be the contact) or a
 * split. Stage 1 examines the whole domain with it, stage 4 (inclusion_search.h) the pieces. Part of `conservative`
 * (inclusion.h), written once for the host and the OpenCL backend.
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
#ifndef CCD_SHARED_INCLUSION_BOX_H
#define CCD_SHARED_INCLUSION_BOX_H

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
/* The other coordinate where the hypotenuse u + v = 1 crosses a box edge at coordinate c: 1 - c one double further
 * out, since the subtraction may round down; but 1 - c = 0 as it is when c = 1, where the subtraction is exact. The
 * double after 0 would be the smallest subnormal, and a subnormal operand costs each product it enters a microcode
 * assist of over a hundred cycles on Intel CPUs (every VF pair's first box has such an edge: it made stage 1 twice
 * cubic64's cost there, reports/narrowphase/stages.md), for a vertex that encloses nothing more. */
static inline double ccd_hypotenuse_crossing(double c) {
  const double exact_or_below = 1 - c;
  return exact_or_below > 0 ? nextafter(exact_or_below, 2.0) : exact_or_below;
}
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
        pu[count] = ccd_clamp(ccd_hypotenuse_crossing(cv[i]), box->u0, box->u1);
        pv[count] = cv[i];
      } else { /* an edge along v at u = cu[i] */
        pu[count] = cu[i];
        pv[count] = ccd_clamp(ccd_hypotenuse_crossing(cu[i]), box->v0, box->v1);
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

/* Whether a plane turning with time separates the box's values from the ball of radius δ: at each time of the box,
 * with λ its fraction of the box's length, the plane normal to n(λ) = (1 - λ)·nA + λ·nB at distance δ|n(λ)|.
 * F is linear in t at each (u, v) and affine in (u, v) at each t, so at each λ the box's F lies in the hull of
 * (1 - λ)·F0 + λ·F1 over its (u, v) vertices (F0, F1: the vertex's values at t0 and t1, the first and second half of
 * `values`), with the same per-axis `error`; n(λ)·F there is a quadratic in λ whose Bernstein coefficients are
 * nA·F0, (nA·F1 + nB·F0)/2 and nB·F1, and δ|n(λ)| plus n(λ)'s share of the error is below the line (1 - λ)·RA +
 * λ·RB (|n(λ)| is convex in λ), RA = δ|nA| + |nA|·error. When the difference of the two, a quadratic with the
 * differences of their Bernstein coefficients (the line's being RA, (RA + RB)/2, RB), is proven positive on
 * [0, 1] (every coefficient positive, or the two ends and AM-GM: below), the box holds no contact. Any nA, nB
 * are sound; with the nearest directions at the box's two ends the plane follows the pair's turn, and what it
 * loses is of second order in the box's length in time, where one fixed plane loses the turn itself (first
 * order): pairs that slide past within a hair of δ are excluded in long boxes instead of thousands of short ones.
 * Rounding: each dot product errs by at most 3.01 u of |n|·|F| (4 u used, as ccd_separated_along), plus half a
 * subnormal per product that underflows (4 per dot product); the sum and halving of the middle coefficient, the
 * rounding of |n| and of the comparison are a few u of the values compared, which CCD_SEPARATION_RELATIVE_SLACK
 * covers. */
static inline int ccd_separated_turning(const ccd_inclusion* s, const ccd_v3* values, int count, ccd_v3 nA, ccd_v3 nB) {
  const double length_a = ccd_norm_above(nA), length_b = ccd_norm_above(nB);
  if (!(length_a > 0) || !(length_b > 0)) return 0;
  const ccd_v3 magnitude_a = ccd_cwise_abs(nA), magnitude_b = ccd_cwise_abs(nB);
  const double reach_a = s->thickness * length_a + ccd_dot(magnitude_a, s->error) + 4 * CCD_DENORM_MIN;
  const double reach_b = s->thickness * length_b + ccd_dot(magnitude_b, s->error) + 4 * CCD_DENORM_MIN;
  const double reach_middle = (reach_a + reach_b) / 2;
  const int vertices = count / 2;
  for (int i = 0; i < vertices; ++i) {
    const ccd_v3 F0 = values[i], F1 = values[vertices + i];
    const ccd_v3 size0 = ccd_cwise_abs(F0), size1 = ccd_cwise_abs(F1);
    const double start = ccd_dot(nA, F0), end = ccd_dot(nB, F1);
    const double middle = (ccd_dot(nA, F1) + ccd_dot(nB, F0)) / 2;
    const double start_bound = 4 * CCD_UNIT_ROUNDOFF * ccd_dot(magnitude_a, size0) + CCD_SEPARATION_RELATIVE_SLACK * (fabs(start) + reach_a);
    const double end_bound = 4 * CCD_UNIT_ROUNDOFF * ccd_dot(magnitude_b, size1) + CCD_SEPARATION_RELATIVE_SLACK * (fabs(end) + reach_b);
    const double middle_bound = 4 * CCD_UNIT_ROUNDOFF * (ccd_dot(magnitude_a, size1) + ccd_dot(magnitude_b, size0)) / 2 + 4 * CCD_DENORM_MIN +
                                CCD_SEPARATION_RELATIVE_SLACK * (fabs(middle) + reach_middle);
    /* Lower bounds of the difference's Bernstein coefficients (the slack terms above cover these subtractions). */
    const double low0 = start - start_bound - reach_a, low1 = middle - middle_bound - reach_middle, low2 = end - end_bound - reach_b;
    if (!(low0 > 0) || !(low2 > 0)) return 0;
    /* With both ends positive, the quadratic low0·(1 - λ)² + 2·low1·λ(1 - λ) + low2·λ² (below the difference, the
     * B's being >= 0) is positive on [0, 1] exactly when low1 > 0 or low1² < low0·low2 (no real root; a negative
     * low1 puts the vertex inside [0, 1]). The products round by u each, which 2^-50 covers, and each may underflow
     * by half a subnormal. */
    if (!(low1 > 0) && !(low0 * low2 * (1 - 0x1p-50) > low1 * low1 * (1 + 0x1p-50) + 4 * CCD_DENORM_MIN)) return 0;
  }
  return 1;
}

/* The box halved along parameter d (0 t, 1 u, 2 v) into *low and *high, each with the next creation order. */
static inline void ccd_halve(ccd_inclusion* s, const ccd_sub_box* box, int d, ccd_sub_box* low, ccd_sub_box* high) {
  *low = *box;
  *high = *box;
  const double lo = ccd_box_bound(box, d, 0), hi = ccd_box_bound(box, d, 1);
  const double middle = lo + (hi - lo) / 2;
  ccd_set_box_bound(low, d, 1, middle);
  ccd_set_box_bound(high, d, 0, middle);
  low->order = s->created++;
  high->order = s->created++;
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
  /* (At δ = 0 the search has nothing for it to save, 2 sub-boxes a pair on the paper's spinning ball, and on the
   * GPU machine its cost raised the public steps' narrow phase by a third: reports/narrowphase/stages.md.) */
  if (s->thickness > 0 && box->t1 > box->t0) {
    double u, v;
    const ccd_v3 start = ccd_nearest_point_at(s, box, box->t0, &u, &v);
    if (ccd_separated_turning(s, values, count, start, ccd_nearest_point_at(s, box, box->t1, &u, &v))) return CCD_EXCLUDED;
  }
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
  ccd_halve(s, box, d, low, high);
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

#endif
