#pragma once
/// @file
/// Squared distances between closed primitives at one instant, in the precision of the variant calling them.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace ccd::narrowphase {

template <class T>
using Vector3 = Eigen::Matrix<T, 3, 1>;

/// Squared distance from p to the closed triangle (a, b, c); degenerate triangles fall back to their edges.
template <class T>
T point_triangle_squared_distance(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b, const Vector3<T>& c);

/// Squared distance between the closed segments [p0, p1] and [q0, q1]; zero-length segments are points.
template <class T>
T segment_segment_squared_distance(const Vector3<T>& p0, const Vector3<T>& p1, const Vector3<T>& q0,
                                   const Vector3<T>& q1);

extern template float point_triangle_squared_distance(const Vector3<float>&, const Vector3<float>&,
                                                      const Vector3<float>&, const Vector3<float>&);
extern template double point_triangle_squared_distance(const Vector3<double>&, const Vector3<double>&,
                                                       const Vector3<double>&, const Vector3<double>&);
extern template float segment_segment_squared_distance(const Vector3<float>&, const Vector3<float>&,
                                                       const Vector3<float>&, const Vector3<float>&);
extern template double segment_segment_squared_distance(const Vector3<double>&, const Vector3<double>&,
                                                        const Vector3<double>&, const Vector3<double>&);

}  // namespace ccd::narrowphase
