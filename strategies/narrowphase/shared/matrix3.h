/* 3×3 matrices for stage 3's proof (inclusion_proof.h): the Jacobian of F and its inverse, in double, written once
 * for the host and the OpenCL backend. */
#ifndef CCD_SHARED_MATRIX3_H
#define CCD_SHARED_MATRIX3_H

#include "strategies/narrowphase/shared/geometry.h"

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

#endif
