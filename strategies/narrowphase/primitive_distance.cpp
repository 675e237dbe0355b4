#include "strategies/narrowphase/primitive_distance.hpp"

#include <algorithm>

namespace ccd::narrowphase {
namespace {

/// The point of segment [a, b] closest to p.
template <class T>
Vector3<T> point_segment_closest(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b) {
  const Vector3<T> ab = b - a;
  const T length2 = ab.squaredNorm();
  if (!(length2 > T(0))) return a;
  const T s = std::clamp((p - a).dot(ab) / length2, T(0), T(1));
  return a + s * ab;
}

}  // namespace

// Region-based closest point (Ericson, "Real-Time Collision Detection", 5.1.5): Voronoi regions of the
// vertices, then of the edges, then the face; only divisions by positive denominators.
template <class T>
ClosestPoints<T> point_triangle_closest_points(const Vector3<T>& p, const Vector3<T>& a, const Vector3<T>& b,
                                               const Vector3<T>& c) {
  const Vector3<T> ab = b - a, ac = c - a, ap = p - a;
  if (!(ab.cross(ac).squaredNorm() > T(0))) {
    ClosestPoints<T> best{p, point_segment_closest(p, a, b)};
    for (const Vector3<T>& q : {point_segment_closest(p, b, c), point_segment_closest(p, c, a)}) {
      if ((p - q).squaredNorm() < (p - best.second).squaredNorm()) best.second = q;
    }
    return best;
  }
  const T d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= T(0) && d2 <= T(0)) return {p, a};
  const Vector3<T> bp = p - b;
  const T d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= T(0) && d4 <= d3) return {p, b};
  const T vc = d1 * d4 - d3 * d2;
  if (vc <= T(0) && d1 >= T(0) && d3 <= T(0)) return {p, point_segment_closest(p, a, b)};
  const Vector3<T> cp = p - c;
  const T d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= T(0) && d5 <= d6) return {p, c};
  const T vb = d5 * d2 - d1 * d6;
  if (vb <= T(0) && d2 >= T(0) && d6 <= T(0)) return {p, point_segment_closest(p, a, c)};
  const T va = d3 * d6 - d5 * d4;
  if (va <= T(0) && (d4 - d3) >= T(0) && (d5 - d6) >= T(0)) return {p, point_segment_closest(p, b, c)};
  const T denominator = va + vb + vc;
  const T v = vb / denominator, w = vc / denominator;
  return {p, a + v * ab + w * ac};
}

// Closest points of two segments (Ericson 5.1.9), with the parallel and zero-length cases handled by clamping.
template <class T>
ClosestPoints<T> segment_segment_closest_points(const Vector3<T>& p0, const Vector3<T>& p1, const Vector3<T>& q0,
                                               const Vector3<T>& q1) {
  const Vector3<T> d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const T a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  T s = 0, t = 0;
  if (!(a > T(0)) && !(e > T(0))) return {p0, q0};
  if (!(a > T(0))) {
    t = std::clamp(f / e, T(0), T(1));
  } else {
    const T c = d1.dot(r);
    if (!(e > T(0))) {
      s = std::clamp(-c / a, T(0), T(1));
    } else {
      const T b = d1.dot(d2);
      const T denominator = a * e - b * b;
      s = denominator > T(0) ? std::clamp((b * f - c * e) / denominator, T(0), T(1)) : T(0);
      t = (b * s + f) / e;
      if (t < T(0)) {
        t = 0;
        s = std::clamp(-c / a, T(0), T(1));
      } else if (t > T(1)) {
        t = 1;
        s = std::clamp((b - c) / a, T(0), T(1));
      }
    }
  }
  return {p0 + s * d1, q0 + t * d2};
}

template ClosestPoints<float> point_triangle_closest_points(const Vector3<float>&, const Vector3<float>&,
                                                           const Vector3<float>&, const Vector3<float>&);
template ClosestPoints<double> point_triangle_closest_points(const Vector3<double>&, const Vector3<double>&,
                                                            const Vector3<double>&, const Vector3<double>&);
template ClosestPoints<float> segment_segment_closest_points(const Vector3<float>&, const Vector3<float>&,
                                                            const Vector3<float>&, const Vector3<float>&);
template ClosestPoints<double> segment_segment_closest_points(const Vector3<double>&, const Vector3<double>&,
                                                             const Vector3<double>&, const Vector3<double>&);

}  // namespace ccd::narrowphase
