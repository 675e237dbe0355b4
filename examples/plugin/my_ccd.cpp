// my-ccd: the template's method, to be replaced by yours. It has the two calls of ipc-toolkit's NarrowPhaseCCD, and
// one macro makes it a plugin that answers queries and whole steps (ccdbench/ccdbench_plugin.hpp says how).
//
// What it computes: the distance at `kSamples` evenly spaced times of the step, in double precision, and a contact
// when one is within the thickness (the first such time is its TOI). Like every sampling method it misses a contact
// that happens between two samples, and its TOI can be late by up to one sample's spacing: ccdbench shows both.
#include <ccdbench/ccdbench_plugin.hpp>

#include <algorithm>

namespace {

using ccdbench::Vector3;

Vector3 lerp(const Vector3& a, const Vector3& b, double t) { return {a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, a.z + (b.z - a.z) * t}; }
Vector3 operator-(const Vector3& a, const Vector3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vector3 operator+(const Vector3& a, const Vector3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vector3 operator*(const Vector3& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(const Vector3& a, const Vector3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/// Squared distance from p to segment ab.
double point_segment(const Vector3& p, const Vector3& a, const Vector3& b) {
  const Vector3 ab = b - a;
  const double length = dot(ab, ab);
  const double t = length > 0 ? std::clamp(dot(p - a, ab) / length, 0.0, 1.0) : 0.0;
  const Vector3 d = p - (a + ab * t);
  return dot(d, d);
}

/// Squared distance from p to triangle abc: to its plane when p projects inside, else to the nearest side.
double point_triangle(const Vector3& p, const Vector3& a, const Vector3& b, const Vector3& c) {
  const Vector3 ab = b - a, ac = c - a, ap = p - a;
  const double d00 = dot(ab, ab), d01 = dot(ab, ac), d11 = dot(ac, ac), d20 = dot(ap, ab), d21 = dot(ap, ac);
  const double denominator = d00 * d11 - d01 * d01;
  if (denominator > 0) {
    const double v = (d11 * d20 - d01 * d21) / denominator, w = (d00 * d21 - d01 * d20) / denominator;
    if (v >= 0 && w >= 0 && v + w <= 1) {
      const Vector3 d = ap - (ab * v + ac * w);
      return dot(d, d);
    }
  }
  return std::min({point_segment(p, a, b), point_segment(p, b, c), point_segment(p, c, a)});
}

/// Squared distance between segments ab and cd: the nearest of the four end-to-segment distances, or of the
/// interior closest points when they fall inside both.
double segment_segment(const Vector3& a, const Vector3& b, const Vector3& c, const Vector3& d) {
  const Vector3 u = b - a, v = d - c, w = a - c;
  const double uu = dot(u, u), uv = dot(u, v), vv = dot(v, v), uw = dot(u, w), vw = dot(v, w);
  const double denominator = uu * vv - uv * uv;
  double best = std::min({point_segment(a, c, d), point_segment(b, c, d), point_segment(c, a, b), point_segment(d, a, b)});
  if (denominator > 0) {
    const double s = (uv * vw - vv * uw) / denominator, t = (uu * vw - uv * uw) / denominator;
    if (s >= 0 && s <= 1 && t >= 0 && t <= 1) {
      const Vector3 e = (a + u * s) - (c + v * t);
      best = std::min(best, dot(e, e));
    }
  }
  return best;
}

class MyCCD {
 public:
  bool point_triangle_ccd(const Vector3& p_t0, const Vector3& t0_t0, const Vector3& t1_t0, const Vector3& t2_t0, const Vector3& p_t1,
                          const Vector3& t0_t1, const Vector3& t1_t1, const Vector3& t2_t1, double& toi, double min_distance, double tmax) const {
    return first_contact(toi, min_distance, tmax, [&](double t) {
      return point_triangle(lerp(p_t0, p_t1, t), lerp(t0_t0, t0_t1, t), lerp(t1_t0, t1_t1, t), lerp(t2_t0, t2_t1, t));
    });
  }
  bool edge_edge_ccd(const Vector3& ea0_t0, const Vector3& ea1_t0, const Vector3& eb0_t0, const Vector3& eb1_t0, const Vector3& ea0_t1,
                     const Vector3& ea1_t1, const Vector3& eb0_t1, const Vector3& eb1_t1, double& toi, double min_distance, double tmax) const {
    return first_contact(toi, min_distance, tmax, [&](double t) {
      return segment_segment(lerp(ea0_t0, ea0_t1, t), lerp(ea1_t0, ea1_t1, t), lerp(eb0_t0, eb0_t1, t), lerp(eb1_t0, eb1_t1, t));
    });
  }

 private:
  static constexpr int kSamples = 32;
  template <class SquaredDistance>
  static bool first_contact(double& toi, double min_distance, double tmax, SquaredDistance squared_distance) {
    for (int k = 0; k <= kSamples; ++k) {
      const double t = tmax * k / kSamples;
      if (squared_distance(t) <= min_distance * min_distance) {
        toi = t;
        return true;
      }
    }
    return false;
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(MyCCD, ccdbench::Vector3, "my-ccd", "0.1",
                               "the template: distance at 33 sample times in double; misses what passes between them",
                               CCDBENCH_THREAD_SAFE | CCDBENCH_REPORTS_TOI)
