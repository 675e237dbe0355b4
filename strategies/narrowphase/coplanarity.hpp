#pragma once
/// @file
/// The coplanarity cubic of a pair, in double, with the narrow phases' own arithmetic (shared/geometry.h, the text the
/// OpenCL kernels compile too): what FCL's answers are explained with (fcl_elementary.cpp), so that "the cubic
/// vanishes" means the same there as in the cubic narrow phases.
///
/// The vectors of the coplanarity condition over the step, from positions at t = 0 (x0) and their change (dx):
///   VF (p, a, b, c): B = b - a, C = c - a, P = p - a.   EE (a0, a1, b0, b1): B = a1 - a0, C = b1 - b0, P = b0 - a0.
/// Each moves linearly (B(t) = B0 + t·dB), so n(t) = B(t) × C(t) = n0 + n1 t + n2 t² and n(t)·P(t) is a cubic.

#include "core/vec.hpp"
#include "strategies/narrowphase/shared.hpp"

#include <array>

namespace ccd::narrowphase {

/// Coefficients c0..c3 of (B × C)·P as a cubic in t.
inline std::array<double, 4> coplanarity_cubic(const std::array<Vec3, 4>& x0, const std::array<Vec3, 4>& dx, bool vertex_face) {
  shared::f64::ccd_v3 s0[4], sd[4];
  for (std::size_t k = 0; k < 4; ++k) {
    s0[k] = shared::to_shared(x0[k]);
    sd[k] = shared::to_shared(dx[k]);
  }
  std::array<double, 4> c{};
  shared::f64::ccd_coplanarity_cubic(s0, sd, vertex_face, c.data());
  return c;
}

}  // namespace ccd::narrowphase
