#include "datasets/procedural/obstacles.hpp"
#include "datasets/procedural/scene_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ccd::datasets::procedural {
namespace {

Setup flag(CommonParameters& c, const SceneParameters& p) {
  const double size = 1.0;
  ShapeMesh cloth = cloth_grid(c.n, size);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double spacing = size / static_cast<double>(c.n - 1);
  for (std::size_t i = 0; i < c.n; ++i) {
    for (std::size_t j = 0; j < c.n; ++j) {
      // Hung in the x-z plane from the pole at x = 0; a tiny seeded ripple breaks the symmetry.
      cloth.positions[i * c.n + j] =
          Vec3(static_cast<double>(j) * spacing, 1e-3 * spacing * (unit(c.random) - 0.5), 1.5 - static_cast<double>(i) * spacing);
    }
  }
  Setup setup;
  setup.thickness = thickness_of(cloth);
  setup.simulator = std::make_unique<ClothSimulator>(settings_for(cloth, c.n));
  const std::size_t first = setup.simulator->add_cloth(c.n, cloth.positions);
  for (std::size_t i = 0; i < c.n; ++i) {
    const Vec3 pinned = cloth.positions[i * c.n];
    setup.simulator->set_kinematic(first + i * c.n, [pinned](double) { return pinned; });
  }
  const double strength = p.at("wind"), phase_a = unit(c.random) * 6.28, phase_b = unit(c.random) * 6.28;
  setup.simulator->set_wind(
      [=](double t) {
        const double gust = 1.0 + 0.4 * std::sin(2.1 * t + phase_a) * std::sin(0.7 * t + phase_b);
        const double heading = 0.3 * std::sin(1.3 * t + phase_b);
        return Vec3(strength * gust * std::cos(heading), strength * gust * std::sin(heading), 0.0);
      },
      0.5, 0.08);
  setup.objects.push_back(cloth_object("flag", cloth, first));
  setup.report = [n = c.n, initial = std::vector<Vec3>()](std::size_t frame, double, const std::vector<std::vector<Vec3>>& x) mutable {
    if (frame == 0) initial = x[0];
    double drift = 0.0, moved = 0.0;
    for (std::size_t k = 0; k < x[0].size(); ++k) {
      if (k % n == 0)
        drift = std::max(drift, (x[0][k] - initial[k]).norm());
      else
        moved += (x[0][k] - initial[k]).norm();
    }
    return Metrics{{"pinned_drift", drift}, {"mean_free_displacement", moved / static_cast<double>(x[0].size() - n)}};
  };
  return setup;
}

}  // namespace

SceneDefinition flag_scene() {
  return {{"flag", "cloth pinned along one side, blown by gusty wind", with_common({{"wind", 8.0, "mean wind speed along +x (m/s)"}})}, flag};
}

}  // namespace ccd::datasets::procedural
