#include "strategies/narrowphase/cubic.hpp"

#include "strategies/narrowphase/shared.hpp"

#include <sstream>

namespace ccd::narrowphase {
namespace {

/// shared/geometry.h's ccd_cubic_test in float (cubic32, rows rounded to float first) or double (cubic64, the
/// OpenCL backend's kernel computes the same).
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
    NarrowPhaseResult result;
    auto finish = [&](const auto& outcome) {
      result.achieved_tolerance = static_cast<double>(outcome.reach) - thickness;
      if (outcome.collides) {
        result.collides = true;
        result.toi = static_cast<double>(outcome.toi);
      }
    };
    if constexpr (sizeof(T) == 4) {
      shared::f32::ccd_v3 cast[8];
      for (std::size_t i = 0; i < 8; ++i) cast[i] = shared::to_shared(Eigen::Vector3f(rows[i].cast<float>()));
      finish(shared::f32::ccd_cubic_test(cast, static_cast<float>(thickness), static_cast<float>(settings_.eta), vertex_face));
    } else {
      const auto shared_rows = shared::to_shared_rows(rows);
      finish(shared::f64::ccd_cubic_test(shared_rows.data(), thickness, settings_.eta, vertex_face));
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
