#pragma once
/// @file
/// Squared distances between closed primitives at one instant, in the precision of the variant calling them.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace ccd::narrowphase {

template <class T>
using Vector3 = Eigen::Matrix<T, 3, 1>;

/// The closest points of two primitives as computed in T: `first` on the first primitive, `second` on the
/// other. Rounded: the computed points may lie a few ulps off their primitives, so |first - second| is an
/// approximation of the distance (neither a lower nor an upper bound); certified uses take only the direction.
template <class T>
struct ClosestPoints {
  Vector3<T> first, second;
};

/// p against the closed triangle (a, b, c); degenerate triangles fall back to their edges.
template <class T>
ClosestPoints<T> point_triangle_closest_points(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b, const Vector3<T>& c);

/// The closed segments [p0, p1] and [q0, q1]; zero-length segments are points.
template <class T>
ClosestPoints<T> segment_segment_closest_points(const Vector3<T>& p0, const Vector3<T>& p1, const Vector3<T>& q0, const Vector3<T>& q1);

/// Squared distance from p to the closed triangle (a, b, c): of its computed closest points.
template <class T>
T point_triangle_squared_distance(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b, const Vector3<T>& c) {
  const ClosestPoints<T> closest = point_triangle_closest_points(p, a, b, c);
  return (closest.first - closest.second).squaredNorm();
}

/// Squared distance between the closed segments [p0, p1] and [q0, q1]: of their computed closest points.
template <class T>
T segment_segment_squared_distance(const Vector3<T>& p0, const Vector3<T>& p1, const Vector3<T>& q0, const Vector3<T>& q1) {
  const ClosestPoints<T> closest = segment_segment_closest_points(p0, p1, q0, q1);
  return (closest.first - closest.second).squaredNorm();
}

extern template ClosestPoints<float> point_triangle_closest_points(const Vector3<float>&, const Vector3<float>&, const Vector3<float>&,
                                                                   const Vector3<float>&);
extern template ClosestPoints<double> point_triangle_closest_points(const Vector3<double>&, const Vector3<double>&, const Vector3<double>&,
                                                                    const Vector3<double>&);
extern template ClosestPoints<float> segment_segment_closest_points(const Vector3<float>&, const Vector3<float>&, const Vector3<float>&,
                                                                    const Vector3<float>&);
extern template ClosestPoints<double> segment_segment_closest_points(const Vector3<double>&, const Vector3<double>&, const Vector3<double>&,
                                                                     const Vector3<double>&);

}  // namespace ccd::narrowphase
