/// @file
/// The classic coplanarity-cubic test (Provot 1997; Bridson et al. 2002), in float (`cubic32`) or double
/// (`cubic64`): the four points are coplanar at the roots of a cubic in t; at each root in [0, 1] and at t = 0
/// and t = 1 the primitives' distance is compared with δ + η. Fast; it misses contacts without a sign change of
/// the cubic (tangential double roots, coplanar motion) and near-misses of the tolerance.

#include "strategies/narrowphase/entry.hpp"
#include "strategies/narrowphase/shared.hpp"

namespace ccd::narrowphase {
namespace {

struct CubicSettings {
  /// η as a fraction of the pair's bounding-box diagonal: the distance tolerance at the candidate times.
  double eta = 1e-6;
};

/// shared/geometry.h's ccd_cubic_test in float (cubic32, rows rounded to float first) or double (cubic64, the
/// OpenCL backend's kernel computes the same).
template <class T>
class Cubic final : public NarrowPhase {
 public:
  explicit Cubic(const CubicSettings& settings) : settings_(settings) {}

  std::string name() const override { return std::string(sizeof(T) == 4 ? "cubic32" : "cubic64") + ":eta=" + format_spec_number(settings_.eta); }
  bool conservative() const override { return false; }
  std::optional<DeviceForm> device_form() const override {
    if constexpr (sizeof(T) == 4) return std::nullopt;  // the kernels are double precision only
    return DeviceForm{DeviceForm::Kernel::cubic64, settings_.eta, 0, 0};
  }

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

template <class T>
NarrowPhaseEntry cubic_entry(std::string name, std::string help) {
  return {std::move(name),
          std::move(help),
          {KeySpec::number("eta", CubicSettings{}.eta, kFractionOfPairRange,
                           "distance tolerance at the candidate times, a fraction of the pair's box diagonal")},
          false,
          {{"eta", {"0", "1e-8", "1e-6", "1e-4", "1e-2"}}},
          [](const SpecReader& keys) -> std::unique_ptr<NarrowPhase> { return std::make_unique<Cubic<T>>(CubicSettings{keys.number("eta")}); }};
}

}  // namespace

std::vector<NarrowPhaseEntry> cubic_entries() {
  return {cubic_entry<float>("cubic32", "the coplanarity cubic in float: fast, misses tangential and coplanar contacts"),
          cubic_entry<double>("cubic64", "the coplanarity cubic in double: fast, misses tangential and coplanar contacts")};
}

}  // namespace ccd::narrowphase
