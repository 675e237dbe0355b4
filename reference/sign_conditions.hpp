#pragma once
/// @file
/// The contract of docs/DESIGN.md §4, written once: "the primitives come within δ at time t" is the union of sign
/// conditions over the closest features. The formulas are templates over the scalar so that the exact path
/// (polynomials in t with rational coefficients) and the filter (intervals with outward rounding) evaluate the
/// very same expressions and can never disagree on what they decide.
///
/// Vertex-face (p against triangle a b c), 7 conditions:
///   0      face interior: |n|² > 0, the projection of p lies in the closed triangle, (n·(p-a))² - δ²|n|² <= 0
///   1..3   edge (u, v) of the face: |e|² > 0, the projection lies on the closed segment, |(p-u)×e|² - δ²|e|² <= 0
///   4..6   corner u: |p-u|² - δ² <= 0
/// Edge-edge (a0 a1 against b0 b1), 9 conditions:
///   0      interiors: |m|² > 0 (m = ea×eb, not parallel), both line parameters in [0, 1], (r·m)² - δ²|m|² <= 0
///   1..4   an endpoint against the other segment (a0|ab, a1|ab, b0|aa, b1|aa), as the VF edge condition
///   5..8   endpoint pairs a0b0, a0b1, a1b0, a1b1: |x-y|² - δ² <= 0
/// The strict guards keep the interior conditions from firing at degenerate instants; those instants are covered
/// by the edge and corner conditions (docs/DESIGN.md §4). Every condition that holds names a real point pair within
/// δ, and the closest point pair always satisfies one of them: the union is exact.

#include <array>

namespace ccd::reference {

/// A 3-vector over any ring-like scalar (rational polynomials, intervals, doubles).
template <class S>
struct Vector3 {
  S x, y, z;
};

template <class S>
Vector3<S> operator-(const Vector3<S>& a, const Vector3<S>& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}

template <class S>
S dot(const Vector3<S>& a, const Vector3<S>& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

template <class S>
Vector3<S> cross(const Vector3<S>& a, const Vector3<S>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

/// |a|², through the scalar's own square() so that intervals give a non-negative enclosure.
template <class S>
S squared_norm(const Vector3<S>& a) {
  return square(a.x) + square(a.y) + square(a.z);
}

/// One sign condition at time t: it holds when guard > 0 (if there is a guard), every `nonnegative` >= 0, and
/// distance <= 0. Interior conditions also carry the signed distance s with distance = s² - δ²·guard, so a
/// filter can certify contact by a sign change of s.
template <class S>
struct SignCondition {
  bool has_guard = false;
  S guard{};
  std::array<S, 4> nonnegative{};
  int nonnegative_count = 0;
  S distance{};
  bool has_signed_distance = false;
  S signed_distance{};
};

inline constexpr int kVertexFaceConditionCount = 7;
inline constexpr int kEdgeEdgeConditionCount = 9;

/// Point p against the closed segment [u, v].
template <class S>
SignCondition<S> point_segment_condition(const Vector3<S>& p, const Vector3<S>& u, const Vector3<S>& v, const S& delta_squared) {
  SignCondition<S> c;
  const Vector3<S> e = v - u;
  c.has_guard = true;
  c.guard = squared_norm(e);
  c.nonnegative[0] = dot(p - u, e);
  c.nonnegative[1] = dot(p - v, u - v);
  c.nonnegative_count = 2;
  c.distance = squared_norm(cross(p - u, e)) - delta_squared * c.guard;
  return c;
}

template <class S>
SignCondition<S> point_point_condition(const Vector3<S>& p, const Vector3<S>& q, const S& delta_squared) {
  SignCondition<S> c;
  c.distance = squared_norm(p - q) - delta_squared;
  return c;
}

/// Condition `index` (0..6, see the file comment) of point p against triangle (a, b, c).
template <class S>
SignCondition<S> vertex_face_condition(int index, const Vector3<S>& p, const Vector3<S>& a, const Vector3<S>& b, const Vector3<S>& c,
                                       const S& delta_squared) {
  if (index == 0) {
    SignCondition<S> f;
    const Vector3<S> n = cross(b - a, c - a);
    f.has_guard = true;
    f.guard = squared_norm(n);
    // |n|² times the barycentric coordinates of p's projection: all >= 0 inside the closed triangle.
    f.nonnegative[0] = dot(cross(b - a, p - a), n);
    f.nonnegative[1] = dot(cross(c - b, p - b), n);
    f.nonnegative[2] = dot(cross(a - c, p - c), n);
    f.nonnegative_count = 3;
    f.has_signed_distance = true;
    f.signed_distance = dot(n, p - a);
    f.distance = square(f.signed_distance) - delta_squared * f.guard;
    return f;
  }
  const Vector3<S>* corners[3] = {&a, &b, &c};
  if (index <= 3) return point_segment_condition(p, *corners[index - 1], *corners[index % 3], delta_squared);
  return point_point_condition(p, *corners[index - 4], delta_squared);
}

/// Condition `index` (0..8, see the file comment) of segment [a0, a1] against segment [b0, b1].
template <class S>
SignCondition<S> edge_edge_condition(int index, const Vector3<S>& a0, const Vector3<S>& a1, const Vector3<S>& b0, const Vector3<S>& b1,
                                     const S& delta_squared) {
  switch (index) {
    case 0: {
      SignCondition<S> c;
      const Vector3<S> ea = a1 - a0, eb = b1 - b0, r = b0 - a0;
      const Vector3<S> m = cross(ea, eb);
      c.has_guard = true;
      c.guard = squared_norm(m);
      // The closest points of the two lines are a0 + s·ea and b0 + u·eb with s = (r×eb)·m / |m|² and
      // u = (r×ea)·m / |m|²; both must lie in [0, 1].
      const S s_numerator = dot(cross(r, eb), m);
      const S u_numerator = dot(cross(r, ea), m);
      c.nonnegative[0] = s_numerator;
      c.nonnegative[1] = c.guard - s_numerator;
      c.nonnegative[2] = u_numerator;
      c.nonnegative[3] = c.guard - u_numerator;
      c.nonnegative_count = 4;
      c.has_signed_distance = true;
      c.signed_distance = dot(r, m);
      c.distance = square(c.signed_distance) - delta_squared * c.guard;
      return c;
    }
    case 1: return point_segment_condition(a0, b0, b1, delta_squared);
    case 2: return point_segment_condition(a1, b0, b1, delta_squared);
    case 3: return point_segment_condition(b0, a0, a1, delta_squared);
    case 4: return point_segment_condition(b1, a0, a1, delta_squared);
    case 5: return point_point_condition(a0, b0, delta_squared);
    case 6: return point_point_condition(a0, b1, delta_squared);
    case 7: return point_point_condition(a1, b0, delta_squared);
    default: return point_point_condition(a1, b1, delta_squared);
  }
}

}  // namespace ccd::reference
