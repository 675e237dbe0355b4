/// @file
/// `advancement`: conservative advancement by minimum separation (the distance-based test a user with a
/// thickness reaches for). From t = 0 it repeatedly measures the distance d between the primitives and advances
/// by (d - δ)/L, where L bounds how fast that distance can shrink; it reports a contact once d <= δ + η. Over each
/// advance the distance stays above δ, so in exact arithmetic it cannot step over a contact. In doubles it is not
/// conservative: each step is rounded down so that its own arithmetic never passes the contact, but the distance it
/// advances by is rounded, so it can miss or report a TOI late by that rounding (no bound on it is derived here).
/// Grazing passes take many steps; the cap then answers "collides".

#include "strategies/narrowphase/entry.hpp"
#include "strategies/narrowphase/primitive_distance.hpp"

#include <algorithm>
#include <cmath>

namespace ccd::narrowphase {
namespace {

struct AdvancementSettings {
  /// η as a fraction of the pair's bounding-box diagonal: the distance at which it stops and reports a contact.
  double eta = 1e-6;
  long max_iterations = 1000;
};

class Advancement final : public NarrowPhase {
 public:
  explicit Advancement(const AdvancementSettings& settings) : settings_(settings) {}

  std::string name() const override {
    return "advancement:eta=" + format_spec_number(settings_.eta) + ":max_iterations=" + std::to_string(settings_.max_iterations);
  }
  bool conservative() const override { return false; }  // up to the rounding of distances
  NarrowPhaseResult vertex_face(const PairRows& rows, double thickness) const override { return test(rows, thickness, true); }
  NarrowPhaseResult edge_edge(const PairRows& rows, double thickness) const override { return test(rows, thickness, false); }

 private:
  NarrowPhaseResult test(const PairRows& rows, double thickness, bool vertex_face) const {
    std::array<Vec3, 4> x0, dx;
    Vec3 lower = rows[0], upper = rows[0];
    for (int k = 0; k < 4; ++k) {
      x0[k] = rows[k];
      dx[k] = rows[k + 4] - rows[k];
    }
    for (const Vec3& row : rows) {
      lower = lower.cwiseMin(row);
      upper = upper.cwiseMax(row);
    }
    // Any point of one primitive moves with a convex combination of its vertices' velocities, so the distance
    // shrinks no faster than the largest relative velocity of a vertex of one against a vertex of the other.
    double speed = 0;
    const int split = vertex_face ? 1 : 2;
    for (int i = 0; i < split; ++i) {
      for (int j = split; j < 4; ++j) speed = std::max(speed, (dx[i] - dx[j]).norm());
    }
    const double stop = thickness + settings_.eta * (upper - lower).norm();
    NarrowPhaseResult result;
    result.achieved_tolerance = stop - thickness;
    double t = 0;
    for (long iteration = 0; iteration < settings_.max_iterations; ++iteration) {
      std::array<Vec3, 4> x;
      for (int k = 0; k < 4; ++k) x[k] = x0[k] + t * dx[k];
      const double distance =
          std::sqrt(vertex_face ? point_triangle_squared_distance(x[0], x[1], x[2], x[3]) : segment_segment_squared_distance(x[0], x[1], x[2], x[3]));
      if (distance <= stop) {
        result.collides = true;
        result.toi = t;
        return result;
      }
      if (t >= 1 || speed == 0) return result;
      // The advance, then two doubles down: the division and the addition each round by at most one ulp of the
      // result (the advance is no larger than the sum), so the rounded step never passes the time the exact step
      // reaches; what is left late is the rounding of the distance itself.
      t = std::clamp(std::nextafter(std::nextafter(t + (distance - thickness) / speed, 0.0), 0.0), t, 1.0);
    }
    result.collides = true;  // the cap: do not claim a miss that was not shown
    result.toi = t;
    result.hit_iteration_cap = true;
    return result;
  }

  AdvancementSettings settings_;
};

}  // namespace

std::vector<NarrowPhaseEntry> advancement_entries() {
  const AdvancementSettings defaults;
  return {
      {"advancement",
       "conservative advancement by minimum separation, in plain doubles: not conservative, it can miss or be late by the rounding of its distances",
       {KeySpec::number("eta", defaults.eta, kFractionOfPairRange,
                        "distance at which it stops and reports a contact, a fraction of the pair's box diagonal"),
        KeySpec::integer("max_iterations", defaults.max_iterations, kIterationRange,
                         "advancement steps before giving up (and answering \"collides\")")},
       false,
       {{"eta", {"0", "1e-8", "1e-6", "1e-4", "1e-2"}}},
       [](const SpecReader& keys) -> std::unique_ptr<NarrowPhase> {
         return std::make_unique<Advancement>(AdvancementSettings{keys.number("eta"), keys.integer("max_iterations")});
       }}};
}

}  // namespace ccd::narrowphase
