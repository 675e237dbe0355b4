#include "datasets/procedural/obstacles.hpp"
#include "datasets/procedural/scene_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ccd::datasets::procedural {
namespace {

Setup twist(CommonParameters& c, const SceneParameters& p) {
  const double size = 1.0, rate = p.at("twist_rate"), squeeze = p.at("squeeze");
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  ShapeMesh cloth = cloth_grid(c.n, size);
  const double spacing = size / static_cast<double>(c.n - 1);
  for (Vec3& v : cloth.positions) v.z() = 1e-3 * spacing * (unit(c.random) - 0.5);
  Setup setup;
  setup.thickness = thickness_of(cloth);
  SimulatorSettings settings = settings_for(cloth, c.n);
  settings.gravity = Vec3(0, 0, 0);
  setup.simulator = std::make_unique<ClothSimulator>(settings);
  const std::size_t first = setup.simulator->add_cloth(c.n, cloth.positions);
  // The two end columns are clamps: they turn in opposite directions about x and move towards each other.
  for (std::size_t i = 0; i < c.n; ++i) {
    for (std::size_t j : {std::size_t{0}, c.n - 1}) {
      const Vec3 rest = cloth.positions[i * c.n + j];
      const double direction = j == 0 ? 1.0 : -1.0;
      setup.simulator->set_kinematic(first + i * c.n + j, [=](double t) {
        const double angle = direction * rate * t;
        const double x = rest.x() * (1.0 - squeeze * std::min(1.0, t));
        return Vec3(x, rest.y() * std::cos(angle) - rest.z() * std::sin(angle), rest.y() * std::sin(angle) + rest.z() * std::cos(angle));
      });
    }
  }
  setup.objects.push_back(cloth_object("mat", cloth, first));
  setup.report = [rate](std::size_t, double t, const std::vector<std::vector<Vec3>>&) {
    return Metrics{{"clamp_angle_deg", 2 * rate * t * 180 / std::numbers::pi}};
  };
  return setup;
}

}  // namespace

SceneDefinition twist_scene() {
  return {{"twist", "a mat whose two ends turn in opposite directions and close in: heavy self-contact",
           with_common({{"twist_rate", 2.5, "each clamp's angular speed about x (rad/s)"},
                        {"squeeze", 0.35, "fraction by which the clamps close in over the first second"}})},
          twist};
}

}  // namespace ccd::datasets::procedural
