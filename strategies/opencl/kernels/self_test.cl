/* The start-up check of a device's arithmetic (strategies/opencl/self_test.cpp): the host gives the inputs and
 * compares every output bit with its own. */

#include "strategies/narrowphase/shared/geometry.h"
#include "strategies/narrowphase/shared/inclusion.h"

/* in: a, b, c, tiny, smallest, two, three. out: a·b + c (0 unless contracted into an FMA), tiny / 2 (a subnormal,
 * 0 if flushed), 3·smallest - smallest (subnormal arithmetic), sqrt(2) and 1/3 (correctly rounded). */
kernel void self_test_arithmetic(global const double* in, global double* out) {
  if (get_global_id(0) != 0) return;
  out[0] = in[0] * in[1] + in[2];
  out[1] = in[3] / in[5];
  out[2] = in[6] * in[4] - in[4];
  out[3] = sqrt(in[5]);
  out[4] = 1.0 / in[6];
}

#ifndef CCD_DEEP_PASS
/* Both narrow phases on `count` pairs (rows: 24 doubles per pair; kinds: 1 for vertex-face), as the host runs them. */
kernel void self_test_pairs(uint count, global const double* rows, global const int* kinds, global const double* thickness, double tolerance,
                            double toi_tolerance, long max_iterations, double eta, global double* out) {
  const uint i = get_global_id(0);
  if (i >= count) return;
  ccd_v3 r[8];
  for (int k = 0; k < 8; ++k) r[k] = ccd_v3_make(rows[24 * i + 3 * k], rows[24 * i + 3 * k + 1], rows[24 * i + 3 * k + 2]);
  ccd_sub_box storage[CCD_DEVICE_SUB_BOXES];
  const ccd_conservative_outcome c =
      ccd_conservative_test(r, thickness[i], kinds[i], tolerance, toi_tolerance, max_iterations, 0, storage, CCD_DEVICE_SUB_BOXES);
  const ccd_cubic_outcome q = ccd_cubic_test(r, thickness[i], eta, kinds[i]);
  out[6 * i] = c.overflow ? -1.0 : (double)c.collides;
  out[6 * i + 1] = c.toi;
  out[6 * i + 2] = c.achieved_tolerance;
  out[6 * i + 3] = (double)q.collides;
  out[6 * i + 4] = q.toi;
  out[6 * i + 5] = q.reach;
}
#endif
