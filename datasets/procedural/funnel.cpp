#include "datasets/procedural/obstacles.hpp"
#include "datasets/procedural/scene_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ccd::datasets::procedural {
namespace {

Setup funnel(CommonParameters& c, const SceneParameters& p) {
  const double r_bottom = 0.12, z_bottom = -0.3, r_top = 0.6, z_top = 0.3, pull = p.at("pull_speed");
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const ShapeMesh cloth = placed_cloth(c.n, 0.8, unit(c.random) * std::numbers::pi / 2, Vec3(0, 0, 0.35));
  Setup setup;
  setup.thickness = thickness_of(cloth);
  setup.simulator = std::make_unique<ClothSimulator>(settings_for(cloth, c.n));
  const std::size_t first = setup.simulator->add_cloth(c.n, cloth.positions);
  // The vertex nearest the centre and its four grid neighbours are pulled straight down, and stop 0.6 below the
  // funnel's bottom, so the cloth ends hanging through it.
  const std::size_t middle = c.n / 2;
  for (auto [di, dj] : {std::pair{0, 0}, {1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
    const std::size_t index = (middle + static_cast<std::size_t>(di)) * c.n + middle + static_cast<std::size_t>(dj);
    const Vec3 start = cloth.positions[index];
    setup.simulator->set_kinematic(first + index, [start, pull, z_bottom](double t) -> Vec3 {
      return Vec3(start.x(), start.y(), std::max(start.z() - pull * t, z_bottom - 0.6));
    });
  }
  setup.simulator->add_obstacle(funnel_obstacle(r_bottom - 0.5 * setup.thickness, z_bottom, r_top - 0.5 * setup.thickness, z_top, p.at("friction")));
  setup.objects.push_back(cloth_object("cloth", cloth, first));
  setup.objects.push_back(static_object("funnel", frustum(r_bottom, z_bottom, r_top, z_top, 48)));
  setup.collidable = {{"cloth", "funnel"}};
  setup.report = [z_bottom](std::size_t, double, const std::vector<std::vector<Vec3>>& x) {
    double lowest = std::numeric_limits<double>::infinity();
    std::size_t below = 0;
    for (const Vec3& v : x[0]) {
      lowest = std::min(lowest, v.z());
      below += v.z() < z_bottom ? 1 : 0;
    }
    return Metrics{{"lowest_z", lowest}, {"vertices_below_funnel", static_cast<double>(below)}};
  };
  return setup;
}

}  // namespace

SceneDefinition funnel_scene() {
  return {{"funnel", "cloth pulled by its centre down through a funnel",
           with_common({{"pull_speed", 0.6, "downward speed of the pulled centre (m/s)"}, {"friction", 0.3, "cloth-funnel friction"}})},
          funnel};
}

}  // namespace ccd::datasets::procedural
