/* The narrow phases' arithmetic, written once for the host (C++) and the OpenCL backend (OpenCL C 1.2), so that
 * both perform the same operations in the same order and give the same answers bit for bit (docs/DESIGN.md §3).
 *
 * This file is real-generic: it is compiled with `ccd_real` = double (both sides) and = float (the host's
 * cubic32). It includes nothing; its environment defines ccd_real, ccd_real_epsilon (the type's machine epsilon)
 * and the functions sqrt and fabs (C++: strategies/narrowphase/shared.hpp; OpenCL: the kernel prelude), and
 * ccd_dot_sums_right: 0 for the order (a0·b0 + a1·b1) + a2·b2, 1 for a0·b0 + (a1·b1 + a2·b2).
 *
 * Rules that keep the two compilers in step:
 *  - every sum is written out in the order the former Eigen code evaluated it: a contiguous 3-vector's dot
 *    product is (a0·b0 + a1·b1) + a2·b2 in double, and a0·b0 + (a1·b1 + a2·b2) in float (ccd_dot_sums_right;
 *    kept so that cubic32, which has no kernel, answers exactly as before);
 *  - no fused multiply-add: OpenCL kernels say `#pragma OPENCL FP_CONTRACT OFF`, the host compiles with
 *    -ffp-contract=off;
 *  - min and max are ternaries with std::min / std::max's semantics, never fmin / fmax (they differ on NaN and
 *    on signed zeros);
 *  - no built-in dot, cross, length or normalize (OpenCL may compute them in any order or precision). */

#ifndef CCD_SHARED_GEOMETRY_H
#define CCD_SHARED_GEOMETRY_H

typedef struct {
  ccd_real c[3];
} ccd_v3;

static inline ccd_v3 ccd_v3_make(ccd_real x, ccd_real y, ccd_real z) {
  ccd_v3 r;
  r.c[0] = x;
  r.c[1] = y;
  r.c[2] = z;
  return r;
}
static inline ccd_v3 ccd_sub(ccd_v3 a, ccd_v3 b) { return ccd_v3_make(a.c[0] - b.c[0], a.c[1] - b.c[1], a.c[2] - b.c[2]); }
static inline ccd_v3 ccd_add(ccd_v3 a, ccd_v3 b) { return ccd_v3_make(a.c[0] + b.c[0], a.c[1] + b.c[1], a.c[2] + b.c[2]); }
static inline ccd_v3 ccd_scale(ccd_real s, ccd_v3 a) { return ccd_v3_make(s * a.c[0], s * a.c[1], s * a.c[2]); }
/* a + t·d, the position at time t of a point moving by d. */
static inline ccd_v3 ccd_along(ccd_v3 a, ccd_real t, ccd_v3 d) { return ccd_add(a, ccd_scale(t, d)); }
static inline ccd_real ccd_dot(ccd_v3 a, ccd_v3 b) {
  return ccd_dot_sums_right ? a.c[0] * b.c[0] + (a.c[1] * b.c[1] + a.c[2] * b.c[2]) : (a.c[0] * b.c[0] + a.c[1] * b.c[1]) + a.c[2] * b.c[2];
}
static inline ccd_real ccd_squared_norm(ccd_v3 a) { return ccd_dot(a, a); }
static inline ccd_real ccd_norm(ccd_v3 a) { return sqrt(ccd_squared_norm(a)); }
static inline ccd_v3 ccd_cross(ccd_v3 a, ccd_v3 b) {
  return ccd_v3_make(a.c[1] * b.c[2] - a.c[2] * b.c[1], a.c[2] * b.c[0] - a.c[0] * b.c[2], a.c[0] * b.c[1] - a.c[1] * b.c[0]);
}
/* std::min(a, b) and std::max(a, b): the first argument unless the second is strictly smaller (larger). */
static inline ccd_real ccd_min(ccd_real a, ccd_real b) { return b < a ? b : a; }
static inline ccd_real ccd_max(ccd_real a, ccd_real b) { return a < b ? b : a; }
/* std::clamp(v, lo, hi). */
static inline ccd_real ccd_clamp(ccd_real v, ccd_real lo, ccd_real hi) { return v < lo ? lo : (hi < v ? hi : v); }
static inline ccd_v3 ccd_cwise_min(ccd_v3 a, ccd_v3 b) {
  return ccd_v3_make(ccd_min(a.c[0], b.c[0]), ccd_min(a.c[1], b.c[1]), ccd_min(a.c[2], b.c[2]));
}
static inline ccd_v3 ccd_cwise_max(ccd_v3 a, ccd_v3 b) {
  return ccd_v3_make(ccd_max(a.c[0], b.c[0]), ccd_max(a.c[1], b.c[1]), ccd_max(a.c[2], b.c[2]));
}
static inline ccd_v3 ccd_cwise_abs(ccd_v3 a) { return ccd_v3_make(fabs(a.c[0]), fabs(a.c[1]), fabs(a.c[2])); }
static inline ccd_real ccd_max_coeff(ccd_v3 a) { return ccd_max(ccd_max(a.c[0], a.c[1]), a.c[2]); }

/* ---- Closest points of closed primitives at one instant (rounded: see primitive_distance.hpp). ---- */

typedef struct {
  ccd_v3 first, second;
} ccd_closest;

/* The point of segment [a, b] closest to p. */
static inline ccd_v3 ccd_point_segment_closest(ccd_v3 p, ccd_v3 a, ccd_v3 b) {
  const ccd_v3 ab = ccd_sub(b, a);
  const ccd_real length2 = ccd_squared_norm(ab);
  if (!(length2 > (ccd_real)0)) return a;
  const ccd_real s = ccd_clamp(ccd_dot(ccd_sub(p, a), ab) / length2, (ccd_real)0, (ccd_real)1);
  return ccd_along(a, s, ab);
}

static inline ccd_closest ccd_closest_pair(ccd_v3 first, ccd_v3 second) {
  ccd_closest r;
  r.first = first;
  r.second = second;
  return r;
}

/* Region-based closest point (Ericson, "Real-Time Collision Detection", 5.1.5): Voronoi regions of the vertices,
 * then of the edges, then the face; only divisions by positive denominators. Degenerate triangles fall back to
 * their edges. */
static inline ccd_closest ccd_point_triangle_closest(ccd_v3 p, ccd_v3 a, ccd_v3 b, ccd_v3 c) {
  const ccd_v3 ab = ccd_sub(b, a), ac = ccd_sub(c, a), ap = ccd_sub(p, a);
  if (!(ccd_squared_norm(ccd_cross(ab, ac)) > (ccd_real)0)) {
    ccd_closest best = ccd_closest_pair(p, ccd_point_segment_closest(p, a, b));
    const ccd_v3 others[2] = {ccd_point_segment_closest(p, b, c), ccd_point_segment_closest(p, c, a)};
    for (int i = 0; i < 2; ++i) {
      if (ccd_squared_norm(ccd_sub(p, others[i])) < ccd_squared_norm(ccd_sub(p, best.second))) best.second = others[i];
    }
    return best;
  }
  const ccd_real d1 = ccd_dot(ab, ap), d2 = ccd_dot(ac, ap);
  if (d1 <= (ccd_real)0 && d2 <= (ccd_real)0) return ccd_closest_pair(p, a);
  const ccd_v3 bp = ccd_sub(p, b);
  const ccd_real d3 = ccd_dot(ab, bp), d4 = ccd_dot(ac, bp);
  if (d3 >= (ccd_real)0 && d4 <= d3) return ccd_closest_pair(p, b);
  const ccd_real vc = d1 * d4 - d3 * d2;
  if (vc <= (ccd_real)0 && d1 >= (ccd_real)0 && d3 <= (ccd_real)0) return ccd_closest_pair(p, ccd_point_segment_closest(p, a, b));
  const ccd_v3 cp = ccd_sub(p, c);
  const ccd_real d5 = ccd_dot(ab, cp), d6 = ccd_dot(ac, cp);
  if (d6 >= (ccd_real)0 && d5 <= d6) return ccd_closest_pair(p, c);
  const ccd_real vb = d5 * d2 - d1 * d6;
  if (vb <= (ccd_real)0 && d2 >= (ccd_real)0 && d6 <= (ccd_real)0) return ccd_closest_pair(p, ccd_point_segment_closest(p, a, c));
  const ccd_real va = d3 * d6 - d5 * d4;
  if (va <= (ccd_real)0 && (d4 - d3) >= (ccd_real)0 && (d5 - d6) >= (ccd_real)0) {
    return ccd_closest_pair(p, ccd_point_segment_closest(p, b, c));
  }
  const ccd_real denominator = va + vb + vc;
  const ccd_real v = vb / denominator, w = vc / denominator;
  return ccd_closest_pair(p, ccd_along(ccd_along(a, v, ab), w, ac));
}

/* Closest points of two segments (Ericson 5.1.9), with the parallel and zero-length cases handled by clamping. */
static inline ccd_closest ccd_segment_segment_closest(ccd_v3 p0, ccd_v3 p1, ccd_v3 q0, ccd_v3 q1) {
  const ccd_v3 d1 = ccd_sub(p1, p0), d2 = ccd_sub(q1, q0), r = ccd_sub(p0, q0);
  const ccd_real a = ccd_squared_norm(d1), e = ccd_squared_norm(d2), f = ccd_dot(d2, r);
  ccd_real s = 0, t = 0;
  if (!(a > (ccd_real)0) && !(e > (ccd_real)0)) return ccd_closest_pair(p0, q0);
  if (!(a > (ccd_real)0)) {
    t = ccd_clamp(f / e, (ccd_real)0, (ccd_real)1);
  } else {
    const ccd_real c = ccd_dot(d1, r);
    if (!(e > (ccd_real)0)) {
      s = ccd_clamp(-c / a, (ccd_real)0, (ccd_real)1);
    } else {
      const ccd_real b = ccd_dot(d1, d2);
      const ccd_real denominator = a * e - b * b;
      s = denominator > (ccd_real)0 ? ccd_clamp((b * f - c * e) / denominator, (ccd_real)0, (ccd_real)1) : (ccd_real)0;
      t = (b * s + f) / e;
      if (t < (ccd_real)0) {
        t = 0;
        s = ccd_clamp(-c / a, (ccd_real)0, (ccd_real)1);
      } else if (t > (ccd_real)1) {
        t = 1;
        s = ccd_clamp((b - c) / a, (ccd_real)0, (ccd_real)1);
      }
    }
  }
  return ccd_closest_pair(ccd_along(p0, s, d1), ccd_along(q0, t, d2));
}

static inline ccd_real ccd_point_triangle_squared_distance(ccd_v3 p, ccd_v3 a, ccd_v3 b, ccd_v3 c) {
  const ccd_closest closest = ccd_point_triangle_closest(p, a, b, c);
  return ccd_squared_norm(ccd_sub(closest.first, closest.second));
}
static inline ccd_real ccd_segment_segment_squared_distance(ccd_v3 p0, ccd_v3 p1, ccd_v3 q0, ccd_v3 q1) {
  const ccd_closest closest = ccd_segment_segment_closest(p0, p1, q0, q1);
  return ccd_squared_norm(ccd_sub(closest.first, closest.second));
}
/* The pair's squared distance at one instant; x holds its four points in row order (VF: p, a, b, c). */
static inline ccd_real ccd_pair_squared_distance(const ccd_v3 x[4], int vertex_face) {
  return vertex_face ? ccd_point_triangle_squared_distance(x[0], x[1], x[2], x[3]) : ccd_segment_segment_squared_distance(x[0], x[1], x[2], x[3]);
}

/* ---- The coplanarity cubic (coplanarity.hpp explains the terms). ---- */

/* Coefficients c0..c3 of (B × C)·P over the step, from positions at t = 0 (x0) and their change (dx):
 *   VF (p, a, b, c): B = b - a, C = c - a, P = p - a.   EE (a0, a1, b0, b1): B = a1 - a0, C = b1 - b0, P = b0 - a0. */
static inline void ccd_coplanarity_cubic(const ccd_v3 x0[4], const ccd_v3 dx[4], int vertex_face, ccd_real c[4]) {
  const int b_to = vertex_face ? 2 : 1, b_from = vertex_face ? 1 : 0;
  const int c_to = 3, c_from = vertex_face ? 1 : 2;
  const int p_to = vertex_face ? 0 : 2, p_from = vertex_face ? 1 : 0;
  const ccd_v3 B0 = ccd_sub(x0[b_to], x0[b_from]), dB = ccd_sub(dx[b_to], dx[b_from]);
  const ccd_v3 C0 = ccd_sub(x0[c_to], x0[c_from]), dC = ccd_sub(dx[c_to], dx[c_from]);
  const ccd_v3 P0 = ccd_sub(x0[p_to], x0[p_from]), dP = ccd_sub(dx[p_to], dx[p_from]);
  const ccd_v3 n0 = ccd_cross(B0, C0);
  const ccd_v3 n1 = ccd_add(ccd_cross(B0, dC), ccd_cross(dB, C0));
  const ccd_v3 n2 = ccd_cross(dB, dC);
  c[0] = ccd_dot(n0, P0);
  c[1] = ccd_dot(n0, dP) + ccd_dot(n1, P0);
  c[2] = ccd_dot(n1, dP) + ccd_dot(n2, P0);
  c[3] = ccd_dot(n2, dP);
}

static inline ccd_real ccd_cubic_value(const ccd_real c[4], ccd_real t) { return ((c[3] * t + c[2]) * t + c[1]) * t + c[0]; }
static inline ccd_real ccd_cubic_slope(const ccd_real c[4], ccd_real t) { return ((ccd_real)3 * c[3] * t + (ccd_real)2 * c[2]) * t + c[1]; }

/* Candidate times, increasing: the cubic's sign-change roots in [0, 1], plus 0 and 1 (at most 5, written to
 * times[6]); returns their count. [0, 1] is split at the roots of the derivative, so every piece is monotone; a
 * piece whose ends differ in sign holds one root, found by Newton steps kept inside a shrinking bracket (a
 * bisection step whenever Newton leaves it). The closed form (Cardano) loses the roots of nearly degenerate
 * cubics, which is what this data has. */
static inline int ccd_cubic_candidate_times(const ccd_real c[4], ccd_real times[6]) {
  ccd_real breaks[4] = {0, 1, 1, 1};
  int count = 1;
  const ccd_real qa = (ccd_real)3 * c[3], qb = (ccd_real)2 * c[2], qc = c[1];
  if (qa != (ccd_real)0) {
    const ccd_real discriminant = qb * qb - (ccd_real)4 * qa * qc;
    if (discriminant > (ccd_real)0) {
      const ccd_real root = sqrt(discriminant);
      /* no cancellation (Numerical Recipes) */
      const ccd_real q = qb >= (ccd_real)0 ? (ccd_real)(-0.5) * (qb + root) : (ccd_real)(-0.5) * (qb - root);
      ccd_real r1 = q / qa, r2 = q != (ccd_real)0 ? qc / q : r1;
      if (r1 > r2) {
        const ccd_real swap = r1;
        r1 = r2;
        r2 = swap;
      }
      if (r1 > (ccd_real)0 && r1 < (ccd_real)1) breaks[count++] = r1;
      if (r2 > (ccd_real)0 && r2 < (ccd_real)1) breaks[count++] = r2;
    }
  } else if (qb != (ccd_real)0) {
    const ccd_real r = -qc / qb;
    if (r > (ccd_real)0 && r < (ccd_real)1) breaks[count++] = r;
  }
  breaks[count++] = 1;

  int found = 0;
  times[found++] = 0;
  for (int i = 0; i + 1 < count; ++i) {
    ccd_real lo = breaks[i], hi = breaks[i + 1];
    ccd_real f_lo = ccd_cubic_value(c, lo);
    const ccd_real f_hi = ccd_cubic_value(c, hi);
    if (f_lo == (ccd_real)0 || f_hi == (ccd_real)0 || (f_lo < (ccd_real)0) == (f_hi < (ccd_real)0)) {
      if (f_hi == (ccd_real)0 && hi < (ccd_real)1) times[found++] = hi;
      continue;
    }
    ccd_real t = lo + (hi - lo) / (ccd_real)2;
    for (int iteration = 0; iteration < 60; ++iteration) {
      const ccd_real value = ccd_cubic_value(c, t);
      if (value == (ccd_real)0) break;
      if ((value < (ccd_real)0) == (f_lo < (ccd_real)0)) {
        lo = t;
        f_lo = value;
      } else {
        hi = t;
      }
      const ccd_real slope = ccd_cubic_slope(c, t);
      ccd_real next = slope != (ccd_real)0 ? t - value / slope : lo;
      if (!(next > lo && next < hi)) next = lo + (hi - lo) / (ccd_real)2;
      if (next == t || hi - lo <= ccd_real_epsilon * hi) {
        t = next;
        break;
      }
      t = next;
    }
    times[found++] = t;
  }
  times[found++] = 1;
  return found; /* increasing already: pieces in order, at most one root each */
}

/* ---- The cubic narrow phases (cubic32, cubic64). ---- */

typedef struct {
  int collides;
  ccd_real toi;
  /* δ + eta·(the pair's bounding-box diagonal): the distance a candidate time must reach. */
  ccd_real reach;
} ccd_cubic_outcome;

/* The coplanarity roots, then a distance check at each candidate time against reach = δ + eta·diagonal (not
 * conservative: a contact between candidate times is missed). rows: the pair in ccd_real, row order. */
static inline ccd_cubic_outcome ccd_cubic_test(const ccd_v3 rows[8], ccd_real thickness, ccd_real eta, int vertex_face) {
  ccd_v3 x0[4], dx[4];
  ccd_v3 lower = rows[0], upper = rows[0];
  for (int k = 0; k < 4; ++k) {
    x0[k] = rows[k];
    dx[k] = ccd_sub(rows[k + 4], x0[k]);
    lower = ccd_cwise_min(ccd_cwise_min(lower, x0[k]), rows[k + 4]);
    upper = ccd_cwise_max(ccd_cwise_max(upper, x0[k]), rows[k + 4]);
  }
  ccd_real coefficients[4];
  ccd_coplanarity_cubic(x0, dx, vertex_face, coefficients);
  ccd_real times[6];
  const int count = ccd_cubic_candidate_times(coefficients, times);
  ccd_cubic_outcome outcome;
  outcome.collides = 0;
  outcome.toi = 0;
  outcome.reach = thickness + eta * ccd_norm(ccd_sub(upper, lower));
  const ccd_real reach2 = outcome.reach * outcome.reach;
  for (int i = 0; i < count; ++i) {
    const ccd_real t = times[i];
    ccd_v3 x[4];
    for (int k = 0; k < 4; ++k) x[k] = ccd_along(x0[k], t, dx[k]);
    if (ccd_pair_squared_distance(x, vertex_face) <= reach2) {
      outcome.collides = 1;
      outcome.toi = t;
      return outcome;
    }
  }
  return outcome;
}

#endif
