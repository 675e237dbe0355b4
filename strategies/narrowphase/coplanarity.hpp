#pragma once
/// @file
/// The coplanarity cubic of a pair and its roots: shared by the cubic variants and by the conservative test,
/// which uses the roots as starting points (never as proof of a miss). The arithmetic is shared/geometry.h's, the
/// same text the OpenCL kernels compile.
///
/// The vectors of the coplanarity condition over the step, from positions at t = 0 (x0) and their change (dx):
///   VF (p, a, b, c): B = b - a, C = c - a, P = p - a.   EE (a0, a1, b0, b1): B = a1 - a0, C = b1 - b0, P = b0 - a0.
/// Each moves linearly (B(t) = B0 + t·dB), so n(t) = B(t) × C(t) = n0 + n1 t + n2 t² and n(t)·P(t) is a cubic.

#include "strategies/narrowphase/shared.hpp"

#include <Eigen/Core>

#include <array>

namespace ccd::narrowphase {

/// Coefficients c0..c3 of (B × C)·P as a cubic in t, in the precision T (float or double).
template <class T>
std::array<T, 4> coplanarity_cubic(const std::array<Eigen::Matrix<T, 3, 1>, 4>& x0,
                                   const std::array<Eigen::Matrix<T, 3, 1>, 4>& dx, bool vertex_face) {
  std::array<T, 4> c{};
  auto run = [&](auto tag) {
    using V = decltype(tag);
    V s0[4], sd[4];
    for (std::size_t k = 0; k < 4; ++k) {
      s0[k] = shared::to_shared(x0[k]);
      sd[k] = shared::to_shared(dx[k]);
    }
    if constexpr (sizeof(T) == 4) {
      shared::f32::ccd_coplanarity_cubic(s0, sd, vertex_face, c.data());
    } else {
      shared::f64::ccd_coplanarity_cubic(s0, sd, vertex_face, c.data());
    }
  };
  if constexpr (sizeof(T) == 4) {
    run(shared::f32::ccd_v3{});
  } else {
    run(shared::f64::ccd_v3{});
  }
  return c;
}

/// Candidate times, increasing: the cubic's sign-change roots in [0, 1], plus 0 and 1 (at most 5); returns their
/// count (shared/geometry.h, ccd_cubic_candidate_times, says how they are found).
template <class T>
int cubic_candidate_times(const std::array<T, 4>& c, std::array<T, 6>& times) {
  if constexpr (sizeof(T) == 4) {
    return shared::f32::ccd_cubic_candidate_times(c.data(), times.data());
  } else {
    return shared::f64::ccd_cubic_candidate_times(c.data(), times.data());
  }
}

}  // namespace ccd::narrowphase
