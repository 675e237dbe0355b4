/* Stage 4 of `conservative` (inclusion.h): certified advancement through each window's start, then the search of
 * sub-boxes within the windows, earliest first, which bounds the TOI from below. Written once for the host and the
 * OpenCL backend. */
#ifndef CCD_SHARED_INCLUSION_SEARCH_H
#define CCD_SHARED_INCLUSION_SEARCH_H

#include "strategies/narrowphase/shared/inclusion_box.h"
#include "strategies/narrowphase/shared/inclusion_windows.h"

/* What a conservative test answers. overflow: the caller's sub-box storage was too small, or the search gave up
 * after give_up_after iterations (then gave_up is 1 too); nothing else is set, and the caller reruns the test with
 * more room or no limit (the search is deterministic, so a rerun gives the answer it would have). */
typedef struct {
  int collides;
  double toi;
  int hit_iteration_cap;
  double achieved_tolerance;
  int overflow;
  int gave_up;
} ccd_conservative_outcome;

static inline ccd_conservative_outcome ccd_outcome_make(int collides, double toi, double achieved_tolerance) {
  ccd_conservative_outcome outcome;
  outcome.collides = collides;
  outcome.toi = toi;
  outcome.hit_iteration_cap = 0;
  outcome.achieved_tolerance = achieved_tolerance;
  outcome.overflow = 0;
  outcome.gave_up = 0;
  return outcome;
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
 * whole window is passed (no contact in it), 1 otherwise (window->t0 moved forward, or not).
 * At δ > 0 a step first tries a longer box: to a little short of the time the nearest point's own gap n·F - δ|n|
 * (linear in time too) would close, but at most CCD_ADVANCE_GROWTH times the longer of the last box proven this way
 * and the step above. It is excluded as ccd_examine excludes any box (along n, or by the plane turning from n to the
 * nearest direction at its end: ccd_separated_turning, sound for any two directions), so a box passed either way
 * holds no contact; only the lengths tried are guesses. A pair sliding past within a hair of δ while its primitives
 * turn is where this matters: the fixed plane loses the turn at the domain's far vertices and stepped a thousandth
 * of the step at a time (24 steps, then some 30 sub-boxes of search on the paper's spinning ball), where the
 * turning plane, losing only second order, passes boxes a hundred times longer (reports/narrowphase/stages.md).
 * At δ = 0 advancement is as it was: the turning plane saves nothing there (ccd_examine). */
#define CCD_ADVANCE_STEPS 24
/* At δ > 0, where the longer boxes keep a step's progress from shrinking to nothing, more steps pay: on the paper's
 * spinning ball the longest test fell from 66 sub-boxes to 59 with 48. At δ = 0 advancement is as it was before the
 * longer boxes, 24 steps. */
#define CCD_ADVANCE_STEPS_AT_THICKNESS 48
/* Of the way to the first vertex's crossing each step goes: short of it, so that the proof at the box's end holds. */
#define CCD_ADVANCE_FRACTION 0.9
/* The longer box's growth over the last one proven, and its shrinking after a failed try. */
#define CCD_ADVANCE_GROWTH 2.0
#define CCD_ADVANCE_SHRINK 0.25
static inline int ccd_advance(ccd_inclusion* s, ccd_window* window) {
  const int vertices = s->vertex_face ? 3 : 4;
  const double cu[4] = {0, 1, 0, 1}, cv[4] = {0, 0, 1, 1};
  double stride = 0; /* the length of the last longer box proven (shrunk after a failed try) */
  const int steps = s->thickness > 0 ? CCD_ADVANCE_STEPS_AT_THICKNESS : CCD_ADVANCE_STEPS;
  for (int step = 0; step < steps; ++step) {
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
    /* The longer box first where there is one (δ > 0), then the step's own: one box per pass of this loop, so
     * that a box's values and tests are written once. */
    double longer = end;
    if (s->thickness > 0) {
      const double start_gap = ccd_dot(n, ccd_f_value(S0, nearest_u, X0, nearest_v, Y0)) - reach;
      const double end_gap = ccd_dot(n, ccd_f_value(S1, nearest_u, X1, nearest_v, Y1)) - reach;
      longer = t + CCD_ADVANCE_GROWTH * ccd_max(stride, end - t);
      if (end_gap < 0) longer = ccd_min(longer, t + (window->t1 - t) * (start_gap / (start_gap - end_gap)) * CCD_ADVANCE_FRACTION);
      longer = ccd_min(longer, window->t1);
    }
    for (int turning = longer > end; turning >= 0; --turning) {
      const double target = turning ? longer : end;
      if (!(target > t)) return 1;
      box.t1 = target;
      ccd_v3 values[2 * CCD_CLIPPED_VERTICES];
      const int count = ccd_box_values(s, &box, values);
      if (ccd_over_budget(s)) return 1;
      double u, v;
      if (ccd_separated_along(s, values, count, n) ||
          (turning && ccd_separated_turning(s, values, count, n, ccd_nearest_point_at(s, &box, target, &u, &v)))) {
        if (turning) stride = target - t;
        if (target >= window->t1) return 0;
        window->t0 = target;
        break;
      }
      if (!turning) return 1;
      stride = (longer - t) * CCD_ADVANCE_SHRINK;
    }
  }
  return 1;
}

static inline ccd_conservative_outcome ccd_window_search(ccd_inclusion* s, const ccd_window* windows, int count, double upper,
                                                         CCD_SUB_BOX_SPACE ccd_sub_box* storage, int capacity) {
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
    /* A box already within toi_tolerance in time is split in (u, v), toward acceptance; but once a contact is proven
     * (upper), what is left is to exclude time up to it: the box is halved in time while it can be. Cut in (u, v)
     * instead, a box whose end comes just before a first touch at δ > 0 can be neither excluded nor accepted (at its
     * start the pair is farther than δ plus the tolerance) until the cuts reach single doubles: 20,000 sub-boxes
     * (the iteration cap) for a pair of the paper's spinning ball that halving in time ends in 4. */
    const double t_middle = box.t0 + (box.t1 - box.t0) / 2;
    if (upper < (double)INFINITY && box.t1 - box.t0 <= s->toi_tolerance && box.t0 < t_middle && t_middle < box.t1) ccd_halve(s, &box, 0, &low, &high);
    if (size + 2 > capacity) {
      result.overflow = 1;
      return result;
    }
    ccd_heap_push(storage, &size, low);
    ccd_heap_push(storage, &size, high);
  }
  if (s->gave_up) {
    result.overflow = 1;
    result.gave_up = 1;
    return result;
  }
  if (size == 0) return result; /* every box excluded: proven no contact */
  result.collides = 1;
  result.hit_iteration_cap = 1;
  result.achieved_tolerance = INFINITY;
  result.toi = ccd_min(storage[0].t0, upper);
  return result;
}

#endif
