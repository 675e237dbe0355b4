#pragma once
/// @file
/// The host's view of the narrow phases' shared arithmetic (shared/*.h; each includes what it uses): the same text
/// the OpenCL kernels compile, here in C++. `f64` holds every function in double, `f32` the real-generic ones in
/// float (cubic32). The files are C on purpose (OpenCL C 1.2 has no templates or namespaces), so C-style casts
/// are silenced for them alone. This project compiles with -ffp-contract=off, which the bit-for-bit parity with
/// the kernels (#pragma OPENCL FP_CONTRACT OFF) needs once a target with FMA is chosen.

#include "core/vec.hpp"

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace ccd::narrowphase::shared {

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wold-style-cast"
#pragma GCC diagnostic ignored "-Wunused-function"
namespace f64 {
using ccd_real = double;
using ccd_ulong = std::uint64_t;
inline constexpr double ccd_real_epsilon = std::numeric_limits<double>::epsilon();
inline constexpr bool ccd_dot_sums_right = false;
using std::ceil;
using std::fabs;
using std::floor;
using std::frexp;
using std::isfinite;
using std::ldexp;
using std::nextafter;
using std::sqrt;
#include "strategies/narrowphase/shared/inclusion.h"
#include "strategies/narrowphase/shared/separation.h"
}  // namespace f64
// geometry.h again, for float: its include guard is reset so that it is read a second time, into namespace f32.
#undef CCD_SHARED_GEOMETRY_H
namespace f32 {
using ccd_real = float;
inline constexpr float ccd_real_epsilon = std::numeric_limits<float>::epsilon();
inline constexpr bool ccd_dot_sums_right = true;
using std::fabs;
using std::sqrt;
#include "strategies/narrowphase/shared/geometry.h"
}  // namespace f32
#pragma GCC diagnostic pop

/// Conversions between Eigen vectors and the shared files' ccd_v3.
inline f64::ccd_v3 to_shared(const Vec3& v) { return f64::ccd_v3_make(v[0], v[1], v[2]); }
inline f32::ccd_v3 to_shared(const Eigen::Vector3f& v) { return f32::ccd_v3_make(v[0], v[1], v[2]); }
inline Vec3 from_shared(const f64::ccd_v3& v) { return {v.c[0], v.c[1], v.c[2]}; }
inline Eigen::Vector3f from_shared(const f32::ccd_v3& v) { return {v.c[0], v.c[1], v.c[2]}; }

/// The eight rows of a pair as the shared files take them.
inline std::array<f64::ccd_v3, 8> to_shared_rows(const std::array<Vec3, 8>& rows) {
  std::array<f64::ccd_v3, 8> out;
  for (int i = 0; i < 8; ++i) out[static_cast<std::size_t>(i)] = to_shared(rows[static_cast<std::size_t>(i)]);
  return out;
}

}  // namespace ccd::narrowphase::shared
