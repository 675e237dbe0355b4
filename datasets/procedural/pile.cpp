#include "datasets/procedural/obstacles.hpp"
#include "datasets/procedural/scene_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ccd::datasets::procedural {
namespace {

/// pile with obstacles=shape: the ground box's half thickness (m), a power of two (see pile).
constexpr double kGroundBoxHalfThickness = 0.03125;

Setup pile(CommonParameters& c, const SceneParameters& p) {
  const auto count = static_cast<std::size_t>(p.at("count"));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<ShapeMesh> cloths;
  for (std::size_t k = 0; k < count; ++k) {
    cloths.push_back(placed_cloth(c.n, 1.0, unit(c.random) * std::numbers::pi,
                                  Vec3((unit(c.random) - 0.5) * 0.2, (unit(c.random) - 0.5) * 0.2, 0.15 + 0.2 * static_cast<double>(k))));
  }
  Setup setup;
  setup.thickness = thickness_of(cloths[0]);
  setup.simulator = std::make_unique<ClothSimulator>(settings_for(cloths[0], c.n));
  setup.simulator->add_obstacle(plane_obstacle(0.5 * setup.thickness, p.at("friction")));
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t first = setup.simulator->add_cloth(c.n, cloths[k].positions);
    setup.objects.push_back(cloth_object("cloth" + std::to_string(k), cloths[k], first));
  }
  if (shape_obstacles(p)) {
    // A thin box under the ground plane whose top face is the ground mesh's square: its centre and half extents
    // are powers of two, so the top face lies exactly at z = 0.
    const Vec3 half(1.5, 1.5, kGroundBoxHalfThickness), centre(0, 0, -kGroundBoxHalfThickness);
    setup.objects.push_back(shape_object(
        "ground", box_shape(half), [centre](double) { return centre; }, true));
  } else {
    ShapeMesh ground{{{-1.5, -1.5, 0}, {1.5, -1.5, 0}, {1.5, 1.5, 0}, {-1.5, 1.5, 0}}, {{0, 1, 2}, {0, 2, 3}}};
    setup.objects.push_back(static_object("ground", std::move(ground)));
  }
  for (std::size_t a = 0; a < count; ++a) {
    setup.collidable.emplace_back("cloth" + std::to_string(a), "ground");
    for (std::size_t b = a + 1; b < count; ++b) setup.collidable.emplace_back("cloth" + std::to_string(a), "cloth" + std::to_string(b));
  }
  setup.report = [count](std::size_t, double, const std::vector<std::vector<Vec3>>& x) {
    Metrics metrics;
    for (std::size_t k = 0; k < count; ++k) {
      double lowest = std::numeric_limits<double>::infinity();
      for (const Vec3& v : x[k]) lowest = std::min(lowest, v.z());
      metrics.emplace_back("cloth" + std::to_string(k) + "_lowest_z", lowest);
    }
    return metrics;
  };
  return setup;
}

}  // namespace

SceneDefinition pile_scene() {
  return {{"pile", "several cloths fall on the ground and on each other: inter-object contact",
           with_common({{"count", 3, "number of cloths"}, {"friction", 0.5, "cloth-ground friction"}, kObstaclesParameter})},
          pile};
}

}  // namespace ccd::datasets::procedural
