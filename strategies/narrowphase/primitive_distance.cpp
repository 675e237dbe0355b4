#include "strategies/narrowphase/primitive_distance.hpp"

#include "strategies/narrowphase/shared.hpp"

namespace ccd::narrowphase {

// The arithmetic is shared/geometry.h's (Ericson, "Real-Time Collision Detection", 5.1.5 and 5.1.9), the same
// text the OpenCL kernels compile.

template <class T>
ClosestPoints<T> point_triangle_closest_points(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b, const Vector3<T>& c) {
  using namespace shared;
  const auto closest = [&] {
    if constexpr (sizeof(T) == 4) {
      return f32::ccd_point_triangle_closest(to_shared(p), to_shared(a), to_shared(b), to_shared(c));
    } else {
      return f64::ccd_point_triangle_closest(to_shared(p), to_shared(a), to_shared(b), to_shared(c));
    }
  }();
  return {from_shared(closest.first), from_shared(closest.second)};
}

template <class T>
ClosestPoints<T> segment_segment_closest_points(const Vector3<T>& p0, const Vector3<T>& p1, const Vector3<T>& q0, const Vector3<T>& q1) {
  using namespace shared;
  const auto closest = [&] {
    if constexpr (sizeof(T) == 4) {
      return f32::ccd_segment_segment_closest(to_shared(p0), to_shared(p1), to_shared(q0), to_shared(q1));
    } else {
      return f64::ccd_segment_segment_closest(to_shared(p0), to_shared(p1), to_shared(q0), to_shared(q1));
    }
  }();
  return {from_shared(closest.first), from_shared(closest.second)};
}

template ClosestPoints<float> point_triangle_closest_points(const Vector3<float>&, const Vector3<float>&, const Vector3<float>&,
                                                            const Vector3<float>&);
template ClosestPoints<double> point_triangle_closest_points(const Vector3<double>&, const Vector3<double>&, const Vector3<double>&,
                                                             const Vector3<double>&);
template ClosestPoints<float> segment_segment_closest_points(const Vector3<float>&, const Vector3<float>&, const Vector3<float>&,
                                                             const Vector3<float>&);
template ClosestPoints<double> segment_segment_closest_points(const Vector3<double>&, const Vector3<double>&, const Vector3<double>&,
                                                              const Vector3<double>&);

}  // namespace ccd::narrowphase
