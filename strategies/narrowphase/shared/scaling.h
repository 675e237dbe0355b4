/* Exact rescaling by a power of two, written once for the host and the OpenCL backend: the conservative narrow
 * phase and the separation filter work on pairs brought to unit size, so that their error bounds are the same at
 * every scale. Multiplying a double by a power of two is exact while the result stays a normal double, so the
 * rescaled pair is the same geometric question (at δ = 0, the same truth): a pair at 2^-960 gets the same answer,
 * at the same cost, as at 2^0 (docs/DESIGN.md §6). Round-to-nearest is assumed (the host sets it first:
 * strategies/narrowphase/round_to_nearest.hpp). Double only; needs its environment's ldexp, frexp, nextafter, fabs
 * and isfinite (geometry.h says where they come from). */
#ifndef CCD_SHARED_SCALING_H
#define CCD_SHARED_SCALING_H

#include "strategies/narrowphase/shared/geometry.h"

/* The unit roundoff of double, u = 2^-53, and the smallest subnormal: the units of every error bound. */
#define CCD_UNIT_ROUNDOFF 0x1p-53
#define CCD_DENORM_MIN 4.9406564584124654e-324
/* After rescaling, every |coordinate| is below 2^CCD_LARGEST_SCALED_EXPONENT even when the pair's own range forces
 * a smaller shift: cubes of differences (the coplanarity terms, up to 6 of them summed) then stay far from
 * overflow. */
#define CCD_LARGEST_SCALED_EXPONENT 300

/* The pair rescaled exactly by 2^-exponent: with the largest |coordinate| in [1/2, 1), or by the largest power of
 * two that keeps the smallest nonzero |coordinate| a normal double. δ is rounded up when its scaled value is not
 * exact. Returns 0 (rows untouched) when no exact rescaling brings every coordinate below
 * 2^CCD_LARGEST_SCALED_EXPONENT, or a coordinate or δ is not finite: conservative callers then answer "collides". */
static inline int ccd_scale_to_unit(ccd_v3 rows[8], double* thickness, int* exponent) {
  *exponent = 0;
  if (!isfinite(*thickness) || *thickness < 0) return 0;
  double largest = 0, smallest = INFINITY;
  for (int i = 0; i < 8; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double magnitude = fabs(rows[i].c[k]);
      if (!isfinite(magnitude)) return 0;
      largest = ccd_max(largest, magnitude);
      if (magnitude > 0) smallest = ccd_min(smallest, magnitude);
    }
  }
  if (largest == 0) return 1; /* every point at the origin: nothing to rescale */
  int largest_exponent = 0, smallest_exponent = 0;
  frexp(largest, &largest_exponent);   /* largest in [2^(e-1), 2^e) */
  frexp(smallest, &smallest_exponent); /* smallest in [2^(e-1), 2^e), also for subnormals */
  int shift = largest_exponent;
  /* Scaling down keeps every bit only while the smallest coordinate stays normal: smallest·2^-shift >= 2^-1022. */
  const int keeps_bits = smallest_exponent - 1 + 1022;
  if (shift > keeps_bits) shift = keeps_bits;
  if (largest_exponent - shift > CCD_LARGEST_SCALED_EXPONENT) return 0;
  const double given = *thickness;
  double scaled = 0;
  if (shift >= -1022 && shift <= 1022) {
    /* Both 2^-shift and 2^shift are normal doubles, so a product with either is the correctly rounded value of
     * the exact one, as ldexp's is: the same bits from one ldexp instead of 26 (the coordinates' products are
     * exact, their results normal and far from overflow by the choice of shift). shift lies in [-1073, 1024]:
     * only pairs whose largest |coordinate| is 2^1022 or more, or below 2^-1023, take the other branch. */
    const double down = ldexp(1.0, -shift), up = ldexp(1.0, shift);
    scaled = given * down;
    for (int i = 0; i < 8; ++i) {
      for (int k = 0; k < 3; ++k) rows[i].c[k] *= down;
    }
    /* δ is not a coordinate: it may lose bits (or overflow). Rounded up, a larger δ only adds false alarms. */
    if (scaled * up < given) scaled = nextafter(scaled, (double)INFINITY);
  } else {
    scaled = ldexp(given, -shift);
    for (int i = 0; i < 8; ++i) {
      for (int k = 0; k < 3; ++k) rows[i].c[k] = ldexp(rows[i].c[k], -shift);
    }
    if (ldexp(scaled, shift) < given) scaled = nextafter(scaled, (double)INFINITY);
  }
  *thickness = scaled;
  *exponent = shift;
  return 1;
}

#endif
