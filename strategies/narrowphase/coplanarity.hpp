#pragma once
/// @file
/// The coplanarity cubic of a pair and its roots: shared by the cubic variants and by the conservative test,
/// which uses the roots as starting points (never as proof of a miss).

#include "strategies/narrowphase/narrow_phase.hpp"

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <utility>

namespace ccd::narrowphase {

/// The vectors of the coplanarity condition over the step, from positions at t = 0 (x0) and their change (dx):
///   VF (p, a, b, c): B = b - a, C = c - a, P = p - a.   EE (a0, a1, b0, b1): B = a1 - a0, C = b1 - b0, P = b0 - a0.
/// Each moves linearly (B(t) = B0 + t·dB), so n(t) = B(t) × C(t) = n0 + n1 t + n2 t² and n(t)·P(t) is a cubic.
template <class T>
struct CoplanarityTerms {
  using V = Eigen::Matrix<T, 3, 1>;
  V B0, dB, C0, dC, P0, dP;
  V n0, n1, n2;

  CoplanarityTerms(const std::array<V, 4>& x0, const std::array<V, 4>& dx, bool vertex_face) {
    auto difference = [&](int to, int from, V& start, V& change) {
      start = x0[to] - x0[from];
      change = dx[to] - dx[from];
    };
    difference(vertex_face ? 2 : 1, vertex_face ? 1 : 0, B0, dB);
    difference(3, vertex_face ? 1 : 2, C0, dC);
    difference(vertex_face ? 0 : 2, vertex_face ? 1 : 0, P0, dP);
    n0 = B0.cross(C0);
    n1 = B0.cross(dC) + dB.cross(C0);
    n2 = dB.cross(dC);
  }

  /// Coefficients c0..c3 of n(t)·P(t).
  std::array<T, 4> cubic() const { return {n0.dot(P0), n0.dot(dP) + n1.dot(P0), n1.dot(dP) + n2.dot(P0), n2.dot(dP)}; }
};

/// Coefficients c0..c3 of (B × C)·P as a cubic in t, in the precision T (CoplanarityTerms).
template <class T>
std::array<T, 4> coplanarity_cubic(const std::array<Eigen::Matrix<T, 3, 1>, 4>& x0,
                                   const std::array<Eigen::Matrix<T, 3, 1>, 4>& dx, bool vertex_face) {
  return CoplanarityTerms<T>(x0, dx, vertex_face).cubic();
}

/// Candidate times, increasing: the cubic's sign-change roots in [0, 1], plus 0 and 1 (at most 5). [0, 1] is split
/// at the roots of the derivative, so every piece is monotone; a piece whose ends differ in sign holds one root,
/// found by Newton steps kept inside a shrinking bracket (a bisection step whenever Newton leaves it). The closed
/// form (Cardano) loses the roots of nearly degenerate cubics, which is what this data has.
template <class T>
int cubic_candidate_times(const std::array<T, 4>& c, std::array<T, 6>& times) {
  auto f = [&](T t) { return ((c[3] * t + c[2]) * t + c[1]) * t + c[0]; };
  auto df = [&](T t) { return (T(3) * c[3] * t + T(2) * c[2]) * t + c[1]; };
  std::array<T, 4> breaks{T(0), T(1), T(1), T(1)};
  int count = 1;
  const T qa = T(3) * c[3], qb = T(2) * c[2], qc = c[1];
  if (qa != T(0)) {
    const T discriminant = qb * qb - T(4) * qa * qc;
    if (discriminant > T(0)) {
      const T root = std::sqrt(discriminant);
      const T q = qb >= T(0) ? T(-0.5) * (qb + root) : T(-0.5) * (qb - root);  // no cancellation (Numerical Recipes)
      T r1 = q / qa, r2 = q != T(0) ? qc / q : r1;
      if (r1 > r2) std::swap(r1, r2);
      for (T r : {r1, r2}) {
        if (r > T(0) && r < T(1)) breaks[count++] = r;
      }
    }
  } else if (qb != T(0)) {
    const T r = -qc / qb;
    if (r > T(0) && r < T(1)) breaks[count++] = r;
  }
  breaks[count++] = T(1);

  int found = 0;
  times[found++] = T(0);
  for (int i = 0; i + 1 < count; ++i) {
    T lo = breaks[i], hi = breaks[i + 1];
    T f_lo = f(lo);
    const T f_hi = f(hi);
    if (f_lo == T(0) || f_hi == T(0) || (f_lo < T(0)) == (f_hi < T(0))) {
      if (f_hi == T(0) && hi < T(1)) times[found++] = hi;
      continue;
    }
    T t = lo + (hi - lo) / T(2);
    for (int iteration = 0; iteration < 60; ++iteration) {
      const T value = f(t);
      if (value == T(0)) break;
      if ((value < T(0)) == (f_lo < T(0))) {
        lo = t;
        f_lo = value;
      } else {
        hi = t;
      }
      const T slope = df(t);
      T next = slope != T(0) ? t - value / slope : lo;
      if (!(next > lo && next < hi)) next = lo + (hi - lo) / T(2);
      if (next == t || hi - lo <= std::numeric_limits<T>::epsilon() * hi) {
        t = next;
        break;
      }
      t = next;
    }
    times[found++] = t;
  }
  times[found++] = T(1);
  return found;  // increasing already: pieces in order, at most one root each
}

}  // namespace ccd::narrowphase
