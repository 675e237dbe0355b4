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
/* A point proven within δ (stage 2) must be so with this relative room: it only ever adds a false alarm. */
#define CCD_PROOF_RELATIVE_SLACK 0x1p-40
/* Stage 0 calls a pair within δ at t = 0 when its squared distance is below δ² by this much of the squared size:
 * the closest-point distance is computed in a few dozen roundings (<< 1e-10); a mistake here would only be a false
 * alarm with TOI 0, never a miss. */
#define CCD_START_DISTANCE_MARGIN 1e-10
/* Boxes spent bounding the TOI below once a contact is proven. */
#define CCD_TOI_BUDGET 48
/* Half-width of the box around a Newton point in which Miranda's theorem proves a zero: about 1e-7 per parameter. */
#define CCD_MIRANDA_HALF_WIDTH 0x1p-24

/* ---- The inclusion search. ---- */

typedef struct {
  ccd_v3 x0[4], dx[4];
  int vertex_face;
  double thickness;
  double tolerance_fraction;
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

static inline void ccd_inclusion_init(ccd_inclusion* s, const ccd_v3 rows[8], double thickness, int vertex_face,
                                      double tolerance_fraction, long max_iterations) {
  ccd_v3 magnitude = ccd_v3_make(0, 0, 0), lower = rows[0], upper = rows[0];
  for (int i = 0; i < 8; ++i) {
    magnitude = ccd_cwise_max(magnitude, ccd_cwise_abs(rows[i]));
    lower = ccd_cwise_min(lower, rows[i]);
    upper = ccd_cwise_max(upper, rows[i]);
  }
  for (int k = 0; k < 4; ++k) {
    s->x0[k] = rows[k];
    s->dx[k] = ccd_sub(rows[k + 4], rows[k]);
  }
  s->vertex_face = vertex_face;
  s->thickness = thickness;
  s->tolerance_fraction = tolerance_fraction;
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
static inline ccd_v3 ccd_f_value(ccd_v3 S, double u, ccd_v3 X, double v, ccd_v3 Y) {
  return ccd_add(ccd_add(S, ccd_scale(u, X)), ccd_scale(v, Y));
}

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
    if (high) box->t1 = value; else box->t0 = value;
  } else if (dimension == 1) {
    if (high) box->u1 = value; else box->u0 = value;
  } else {
    if (high) box->v1 = value; else box->v0 = value;
  }
}

/* Excluded (no contact in the box), accepted (every point within δ + tolerance; *achieved is set), or split into
 * *low and *high. */
static inline int ccd_examine(ccd_inclusion* s, const ccd_sub_box* box, ccd_sub_box* low, ccd_sub_box* high, double* achieved) {
  if (s->vertex_face && box->u0 + box->v0 > 1) return CCD_EXCLUDED; /* exact: 1 is representable */
  ccd_v3 F[8];
  ccd_corners(s, box, F);
  ccd_v3 f_min = F[0], f_max = F[0];
  for (int i = 0; i < 8; ++i) {
    f_min = ccd_cwise_min(f_min, F[i]);
    f_max = ccd_cwise_max(f_max, F[i]);
  }
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
  if (farthest2 <= reach * reach || d < 0) {
    *achieved = ccd_max(0.0, sqrt(farthest2) - s->thickness);
    return CCD_ACCEPTED;
  }
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
static inline double ccd_m3_row_dot(const ccd_m3* a, int i, ccd_v3 x) {
  return a->m[i][0] * x.c[0] + (a->m[i][1] * x.c[1] + a->m[i][2] * x.c[2]);
}

/* Miranda's theorem in a small box around (t, u, v): returns 1 and the box's t0 in *toi when it proves a zero. */
static inline int ccd_miranda(const ccd_inclusion* s, double t, double u, double v, ccd_v3 dS, ccd_v3 dX, ccd_v3 dY, double* toi) {
  const double w = CCD_MIRANDA_HALF_WIDTH;
  const ccd_sub_box box = ccd_sub_box_make(t - w, t + w, u - w, u + w, v - w, v + w, 0);
  if (box.t0 < 0 || box.t1 > 1 || !ccd_in_domain(s, box.u0, box.v0) || !ccd_in_domain(s, box.u1, box.v1) ||
      !ccd_in_domain(s, box.u0, box.v1) || !ccd_in_domain(s, box.u1, box.v0)) {
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
      const int negative = g + bound < 0, positive = g - bound > 0;
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
  *toi = box.t0;
  return 1;
}

/* Stage 2: the time of a contact proven cheaply (returns 1 and *earliest), or 0. Starting from the coplanarity
 * cubic's roots, Newton steps locate a zero of F; Miranda's theorem then proves one in a small box around it: with
 * A the inverse Jacobian there, each component G_i of G = A·F is <= 0 on one face of the box across parameter i
 * and >= 0 on the opposite face. G is trilinear, so its extremes on a face are at the face's corners, which are box
 * corners. For δ > 0 a domain point with |F| <= δ proves a contact by itself. A mistake here could only add a
 * false alarm: answers "no" come from exclusions alone. */
static inline int ccd_certify(const ccd_inclusion* s, double* earliest) {
  double cubic[4];
  ccd_coplanarity_cubic(s->x0, s->dx, s->vertex_face, cubic);
  double times[6];
  const int count = ccd_cubic_candidate_times(cubic, times);
  ccd_v3 dS, dX, dY;
  ccd_split_terms(s, s->dx, &dS, &dX, &dY);
  int found = 0;
  for (int i = 0; i < count; ++i) {
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
    if (s->thickness > 0 && ccd_point_within_thickness(s, t, u, v)) {
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

/* A lower bound of the earliest contact: boxes with t < limit are examined earliest first; the first one that
 * cannot be excluded (or whatever remains when the budget runs out) bounds the TOI from below. */
static inline double ccd_earliest_possible(ccd_inclusion* s, double limit, long budget, ccd_sub_box* storage, int capacity, int* overflow) {
  int size = 0;
  ccd_heap_push(storage, &size, ccd_sub_box_make(0, limit, 0, 1, 0, 1, s->created++));
  while (size > 0) {
    if (budget-- <= 0 || ccd_over_budget(s)) {
      if (s->gave_up) *overflow = 1;
      return storage[0].t0;
    }
    const ccd_sub_box box = ccd_heap_pop(storage, &size);
    ccd_sub_box low, high;
    double achieved = 0;
    const int verdict = ccd_examine(s, &box, &low, &high, &achieved);
    if (verdict == CCD_ACCEPTED) return box.t0;
    if (verdict == CCD_SPLIT) {
      if (size + 2 > capacity) {
        *overflow = 1;
        return 0;
      }
      ccd_heap_push(storage, &size, low);
      ccd_heap_push(storage, &size, high);
    }
  }
  return limit;
}

/* Stage 3: the whole search. Depth first with the earlier half on top: reach a contact (or prove there is none)
 * quickly; then, since a contact in a pending box lies at t >= its t0, the TOI is the smallest t0 of an accepted
 * box or a pending one: boxes that start earlier than the TOI found so far are examined, earliest first. */
static inline ccd_conservative_outcome ccd_full_search(ccd_inclusion* s, ccd_sub_box* storage, int capacity) {
  ccd_conservative_outcome result = ccd_outcome_make(0, NAN, 0);
  int size = 0;
  storage[size++] = ccd_sub_box_make(0, 1, 0, 1, 0, 1, s->created++);
  double toi = INFINITY;
  while (size > 0) {
    if (ccd_over_budget(s)) break;
    const ccd_sub_box box = storage[--size];
    ccd_sub_box low, high;
    const int verdict = ccd_examine(s, &box, &low, &high, &result.achieved_tolerance);
    if (verdict == CCD_EXCLUDED) continue;
    if (verdict == CCD_ACCEPTED) {
      toi = box.t0;
      break;
    }
    if (size + 2 > capacity) {
      result.overflow = 1;
      return result;
    }
    storage[size++] = high;
    storage[size++] = low;
  }
  if (s->gave_up) {
    result.overflow = 1;
    return result;
  }
  if (size == 0 && !isfinite(toi)) return result; /* every box excluded: proven no contact */
  result.collides = 1;
  ccd_heapify(storage, size);
  while (size > 0 && storage[0].t0 < toi) {
    if (ccd_over_budget(s)) break;
    const ccd_sub_box box = ccd_heap_pop(storage, &size);
    ccd_sub_box low, high;
    double achieved = 0;
    const int verdict = ccd_examine(s, &box, &low, &high, &achieved);
    if (verdict == CCD_EXCLUDED) continue;
    if (verdict == CCD_ACCEPTED) {
      toi = box.t0;
      result.achieved_tolerance = achieved;
      continue;
    }
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
  result.hit_iteration_cap = s->iterations > s->max_iterations;
  if (result.hit_iteration_cap) result.achieved_tolerance = INFINITY;
  result.toi = size == 0 ? toi : ccd_min(toi, storage[0].t0);
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

/* The whole conservative test of one pair (the `conservative` narrow phase, inclusion.cpp): rescale, stage 0, stage 1 (the whole domain at once
 * excludes far pairs), stage 2 (a cheap proof of a contact, then only a lower bound of its TOI with a small
 * budget), stage 3 (the full search). `storage` holds `capacity` sub-boxes; on overflow the caller retries with
 * more. give_up_after > 0 ends a long search with an overflow (the caller reruns it with 0). Runs in
 * round-to-nearest (the caller's duty on the host; the only mode on an OpenCL device). */
static inline ccd_conservative_outcome ccd_conservative_test(const ccd_v3 original[8], double thickness_given, int vertex_face,
                                                             double tolerance_fraction, long max_iterations, long give_up_after,
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
  ccd_inclusion_init(&search, rows, thickness, vertex_face, tolerance_fraction, max_iterations);
  search.give_up_after = give_up_after;
  const ccd_sub_box root = ccd_sub_box_make(0, 1, 0, 1, 0, 1, 0);
  ccd_sub_box low, high;
  double achieved = 0;
  ccd_over_budget(&search);
  if (ccd_examine(&search, &root, &low, &high, &achieved) == CCD_EXCLUDED) {
    result.collides = 0;
    result.toi = NAN;
    return result;
  }
  double proven = 0;
  if (ccd_certify(&search, &proven)) {
    /* A contact proven at t = 0 is the earliest there can be; otherwise bound the TOI from below. */
    result.toi = proven <= 0 ? 0.0 : ccd_earliest_possible(&search, proven, CCD_TOI_BUDGET, storage, capacity, &result.overflow);
    return result;
  }
  result = ccd_full_search(&search, storage, capacity);
  if (!result.overflow) result.achieved_tolerance = ldexp(result.achieved_tolerance, exponent); /* the pair's units */
  return result;
}

#endif
