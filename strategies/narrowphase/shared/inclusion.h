/* `conservative`, the inclusion-based narrow phase, written once for the host and the OpenCL backend (geometry.h
 * says how the two stay bit-identical). Double only: ccd_real = double, with a 64-bit unsigned `ccd_ulong` and the
 * functions sqrt, fabs, frexp, ldexp, nextafter and isfinite from its environment.
 *
 * The pair as one function F(t, u, v) of time and the primitives' parameters, and F's error bound:
 * inclusion_box.h, which also examines one sub-box (stage 1 applies it to the whole domain). Stage 2, the time
 * windows: inclusion_windows.h. Stage 3, a cheap proof of a contact: inclusion_proof.h (with matrix3.h). Stage 4,
 * advancement and the search within the windows: inclusion_search.h. Stage 0 and the test of one pair, which runs
 * them in order: here. */
#ifndef CCD_SHARED_INCLUSION_H
#define CCD_SHARED_INCLUSION_H

#include "strategies/narrowphase/shared/inclusion_box.h"
#include "strategies/narrowphase/shared/inclusion_proof.h"
#include "strategies/narrowphase/shared/inclusion_search.h"
#include "strategies/narrowphase/shared/inclusion_windows.h"
#include "strategies/narrowphase/shared/scaling.h"

/* Where the test of one pair ended: a hook for profiling (benchmarks/conservative_stages.cpp, which defines it in
 * its own copy of this text); nothing else defines it, so it costs the narrow phase nothing. Stages as below, 5 for
 * advancement that passed every window; `search` is the state (its iterations), or 0 before there is one. */
#ifndef CCD_DECIDED_AT
#define CCD_DECIDED_AT(stage, search)
#endif

/* Stage 0 calls a pair within δ at t = 0 when its squared distance is below δ² by this much of the squared size:
 * the closest-point distance is computed in a few dozen roundings (<< 1e-10); a mistake here would only be a false
 * alarm with TOI 0, never a miss. */
#define CCD_START_DISTANCE_MARGIN 1e-10

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

/* The whole conservative test of one pair (the `conservative` narrow phase, inclusion.cpp): rescale; stage 1 (the
 * whole domain at once excludes far pairs); stage 0 (a pair within δ at the start); stage 2 (the time windows: most
 * pairs that come close without touching end here); stage 3 (a cheap proof of a contact, which bounds the TOI from
 * above, or ends the test where advancement came within toi_tolerance of it); stage 4 (the search within the windows, which bounds it from below). `storage` holds `capacity`
 * sub-boxes; on overflow the caller retries with more. give_up_after > 0 ends a long search with an overflow (the
 * caller reruns it with 0). Runs in round-to-nearest (the caller's duty on the host; the only mode on an OpenCL
 * device). */
static inline ccd_conservative_outcome ccd_conservative_test(const ccd_v3 original[8], double thickness_given, int vertex_face,
                                                             double tolerance_fraction, double toi_tolerance, long max_iterations, long give_up_after,
                                                             CCD_SUB_BOX_SPACE ccd_sub_box* storage, int capacity) {
  ccd_conservative_outcome result = ccd_outcome_make(1, 0, INFINITY);
  ccd_v3 rows[8];
  for (int i = 0; i < 8; ++i) rows[i] = original[i];
  double thickness = thickness_given;
  int exponent = 0;
  if (!ccd_scale_to_unit(rows, &thickness, &exponent)) return result; /* unscalable: never a miss */
  result.achieved_tolerance = 0;
  ccd_inclusion search;
  ccd_inclusion_init(&search, rows, thickness, vertex_face, tolerance_fraction, toi_tolerance, max_iterations);
  search.give_up_after = give_up_after;
  const ccd_sub_box root = ccd_sub_box_make(0, 1, 0, 1, 0, 1, 0);
  ccd_sub_box low, high;
  double achieved = 0;
  ccd_over_budget(&search);
  /* Stage 1 before stage 0, although stage 0 is named first: nearly every pair ends in stage 1, and stage 0's
   * closest-point distance was a fifth of their cost at δ > 0 (reports/narrowphase/stages.md). The order changes
   * no answer: stage 1 excludes a pair only when |F| > δ is proven over the whole domain, t = 0 included, and stage
   * 0 fires only on a distance at t = 0 below δ by far more than its rounding, so no pair can meet both. */
  if (ccd_examine(&search, &root, &low, &high, &achieved) == CCD_EXCLUDED) {
    CCD_DECIDED_AT(1, &search);
    return ccd_outcome_make(0, NAN, 0);
  }
  if (ccd_within_thickness_at_start(rows, thickness, vertex_face)) {
    CCD_DECIDED_AT(0, 0);
    return result;
  }
  ccd_window windows[CCD_MAX_WINDOWS];
  int count = ccd_time_windows(&search, windows);
  if (count == 0) {
    CCD_DECIDED_AT(2, &search);
    return ccd_outcome_make(0, NAN, 0);
  }
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
    result.gave_up = 1;
    return result;
  }
  if (count == 0) {
    CCD_DECIDED_AT(5, &search);
    return ccd_outcome_make(0, NAN, 0);
  }
  /* Newton's starting times: each window's middle, and its start too when it is long enough to matter; at δ > 0
   * first a time `soon` after its start, no more than toi_tolerance past it, where advancement has usually brought a
   * first touch within reach: a point within δ proven there ends the test (below). soon - t0 is exact where
   * t0 >= toi_tolerance (Sterbenz), and one double less when it rounded past toi_tolerance; below, the 2^-40 of
   * toi_tolerance held back exceeds the sum's rounding (an ulp of 2e-6, 2^-71). */
  double seeds[3 * CCD_MAX_WINDOWS];
  int seed_count = 0;
  int soon_first = 0; /* whether seeds[0] is the first window's `soon` */
  for (int i = 0; i < count; ++i) {
    const double length = windows[i].t1 - windows[i].t0;
    if (thickness > 0 && toi_tolerance < length / 2) {
      double soon = windows[i].t0 + toi_tolerance * (1 - 0x1p-40);
      if (soon - windows[i].t0 > toi_tolerance) soon = nextafter(soon, 0.0);
      if (i == 0) soon_first = 1;
      seeds[seed_count++] = soon;
    }
    if (length > CCD_MIRANDA_HALF_WIDTH) seeds[seed_count++] = windows[i].t0;
    seeds[seed_count++] = windows[i].t0 + length / 2;
  }
  double upper = INFINITY;
  if (ccd_certify(&search, seeds, seed_count, &upper)) {
    if (upper <= 0) {
      CCD_DECIDED_AT(3, &search);
      return result; /* a contact proven at t = 0 is the earliest there can be */
    }
    /* A contact proven no more than toi_tolerance after the first window's start (the first seed, `soon`, at
     * δ > 0), before which nothing touches (stages 1 and 2 and advancement excluded it): that start is the TOI,
     * never late and within toi_tolerance of the proven contact, the search's own answer (its top box against
     * upper) without its ~20 halvings in time. */
    if (soon_first && upper <= seeds[0]) {
      CCD_DECIDED_AT(3, &search);
      return ccd_outcome_make(1, windows[0].t0, 0);
    }
    /* The proven contact lies in a window too: no later than the last window time up to upper. */
    double latest = -1;
    for (int i = 0; i < count; ++i) {
      if (windows[i].t0 <= upper) latest = ccd_max(latest, ccd_min(windows[i].t1, upper));
    }
    if (latest >= 0) upper = latest;
  }
  result = ccd_window_search(&search, windows, count, upper, storage, capacity);
  CCD_DECIDED_AT(4, &search);
  if (!result.overflow) result.achieved_tolerance = ldexp(result.achieved_tolerance, exponent); /* the pair's units */
  return result;
}

#endif
