#include "strategies/fcl/fcl_elementary.hpp"

#include "strategies/narrowphase/coplanarity.hpp"

#include <fcl/narrowphase/detail/traversal/collision/intersect.h>

#include <algorithm>
#include <cmath>

namespace ccd::strategies {
namespace {

using Intersect = fcl::detail::Intersect<double>;

bool fcl_answer(const narrowphase::PairRows& rows, bool vertex_face) { return vertex_face ? fcl_vertex_face(rows) : fcl_edge_edge(rows); }

// FCL 0.7's near-zero threshold (intersect-inl.h: getNearZeroThreshold, private there).
constexpr double kFclNearZero = 1e-7;

}  // namespace

bool fcl_vertex_face(const narrowphase::PairRows& r) {
  double time = 0;
  fcl::Vector3<double> point;
  // FCL's order: the face's corners, then the vertex; t = 0 then t = 1.
  return Intersect::intersect_VF(r[1], r[2], r[3], r[0], r[5], r[6], r[7], r[4], &time, &point);
}

bool fcl_edge_edge(const narrowphase::PairRows& r) {
  double time = 0;
  fcl::Vector3<double> point;
  return Intersect::intersect_EE(r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], &time, &point);
}

std::string_view to_string(FclMissCause cause) {
  switch (cause) {
    case FclMissCause::none: return "none";
    case FclMissCause::near_zero_cubic: return "near-zero-cubic";
    case FclMissCause::parallel_threshold: return "parallel-threshold";
    case FclMissCause::coplanar_motion: return "coplanar-motion";
    case FclMissCause::root_rejected: return "root-rejected";
  }
  return "?";
}

FclMissCause explain_fcl_answer(const narrowphase::PairRows& rows, bool vertex_face) {
  if (fcl_answer(rows, vertex_face)) return FclMissCause::none;
  bool found_when_scaled = false;
  for (int exponent : {10, 20, 30}) {
    narrowphase::PairRows scaled = rows;
    for (Vec3& row : scaled) row = row * std::ldexp(1.0, exponent);  // exact: a power of two
    found_when_scaled = found_when_scaled || fcl_answer(scaled, vertex_face);
  }
  std::array<Vec3, 4> x0, dx;
  for (int i = 0; i < 4; ++i) {
    x0[i] = rows[i];
    dx[i] = rows[i + 4] - rows[i];
  }
  const std::array<double, 4> c = narrowphase::coplanarity_cubic(x0, dx, vertex_face);
  double largest = 0, span = 0;
  for (double coefficient : c) largest = std::max(largest, std::abs(coefficient));
  for (const Vec3& row : rows) span = std::max(span, (row - rows[0]).cwiseAbs().maxCoeff());
  if (!found_when_scaled) {
    // Rounding noise of a cubic in three length differences is about 1e-16·span³ (scale-free: relative to
    // span³); a cubic within kCoplanarNoise of it is the coplanar motion FCL cannot see. Only names a cause.
    constexpr double kCoplanarNoise = 1e-12;
    return largest <= kCoplanarNoise * span * span * span ? FclMissCause::coplanar_motion : FclMissCause::root_rejected;
  }
  if (largest < kFclNearZero) return FclMissCause::near_zero_cubic;
  return vertex_face ? FclMissCause::root_rejected : FclMissCause::parallel_threshold;
}

}  // namespace ccd::strategies
