/* Stage 2 of `conservative` (inclusion.h): the time windows where a contact is possible at all, from the
 * coplanarity cubic in Bernstein form. Written once for the host and the OpenCL backend. */
#ifndef CCD_SHARED_INCLUSION_WINDOWS_H
#define CCD_SHARED_INCLUSION_WINDOWS_H

#include "strategies/narrowphase/shared/inclusion_box.h"

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

#endif
