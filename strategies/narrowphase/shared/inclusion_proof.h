/* Stage 3 of `conservative` (inclusion.h): a cheap proof of a contact, Newton steps and Miranda's theorem, which
 * bounds the TOI from above. Written once for the host and the OpenCL backend. */
#ifndef CCD_SHARED_INCLUSION_PROOF_H
#define CCD_SHARED_INCLUSION_PROOF_H

#include "strategies/narrowphase/shared/inclusion_box.h"
#include "strategies/narrowphase/shared/matrix3.h"

/* Half-width of the box around a Newton point in which Miranda's theorem proves a zero: about 1e-7 per parameter. */
#define CCD_MIRANDA_HALF_WIDTH 0x1p-24

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

#endif
