#include "strategies/narrowphase/cubic.hpp"

#include "strategies/narrowphase/coplanarity.hpp"
#include "strategies/narrowphase/primitive_distance.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace ccd::narrowphase {
namespace {

template <class T>
class Cubic final : public NarrowPhase {
 public:
  explicit Cubic(const CubicSettings& settings) : settings_(settings) {}

  std::string name() const override {
    std::ostringstream out;
    out << (sizeof(T) == 4 ? "cubic32" : "cubic64") << ":eta=" << settings_.eta;
    return out.str();
  }
  bool conservative() const override { return false; }

  NarrowPhaseResult vertex_face(const PairRows& rows, double thickness) const override { return test(rows, thickness, true); }
  NarrowPhaseResult edge_edge(const PairRows& rows, double thickness) const override { return test(rows, thickness, false); }

 private:
  NarrowPhaseResult test(const PairRows& rows, double thickness, bool vertex_face) const {
    std::array<Vector3<T>, 4> x0, dx;
    Vector3<T> lower = rows[0].cast<T>(), upper = lower;
    for (int k = 0; k < 4; ++k) {
      x0[k] = rows[k].cast<T>();
      dx[k] = rows[k + 4].cast<T>() - x0[k];
      for (const Vector3<T>& p : {x0[k], Vector3<T>(rows[k + 4].cast<T>())}) {
        lower = lower.cwiseMin(p);
        upper = upper.cwiseMax(p);
      }
    }
    const std::array<T, 4> coefficients = coplanarity_cubic<T>(x0, dx, vertex_face);
    std::array<T, 6> times{};
    const int count = cubic_candidate_times(coefficients, times);

    const T reach = static_cast<T>(thickness) + static_cast<T>(settings_.eta) * (upper - lower).norm();
    const T reach2 = reach * reach;
    NarrowPhaseResult result;
    result.achieved_tolerance = static_cast<double>(reach) - thickness;
    for (int i = 0; i < count; ++i) {
      const T t = times[i];
      std::array<Vector3<T>, 4> x;
      for (int k = 0; k < 4; ++k) x[k] = x0[k] + t * dx[k];
      const T distance2 = vertex_face ? point_triangle_squared_distance(x[0], x[1], x[2], x[3])
                                      : segment_segment_squared_distance(x[0], x[1], x[2], x[3]);
      if (distance2 <= reach2) {
        result.collides = true;
        result.toi = static_cast<double>(t);
        return result;
      }
    }
    return result;
  }

  CubicSettings settings_;
};

}  // namespace

std::unique_ptr<NarrowPhase> make_cubic(bool single_precision, const CubicSettings& settings) {
  if (single_precision) return std::make_unique<Cubic<float>>(settings);
  return std::make_unique<Cubic<double>>(settings);
}

}  // namespace ccd::narrowphase
