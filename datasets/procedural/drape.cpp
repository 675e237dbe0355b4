#include "datasets/procedural/obstacles.hpp"
#include "datasets/procedural/scene_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ccd::datasets::procedural {
namespace {

Setup drape(CommonParameters& c, const SceneParameters& p) {
  const double width = p.at("table_width"), depth = p.at("table_depth");
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const ShapeMesh cloth =
      placed_cloth(c.n, 1.4 * width, (unit(c.random) - 0.5) * 0.3, Vec3((unit(c.random) - 0.5) * 0.1, (unit(c.random) - 0.5) * 0.1, 0.1));
  Setup setup;
  setup.thickness = thickness_of(cloth);
  setup.simulator = std::make_unique<ClothSimulator>(settings_for(cloth, c.n));
  const std::size_t first = setup.simulator->add_cloth(c.n, cloth.positions);
  const Vec3 lower(-width / 2, -depth / 2, -0.75), upper(width / 2, depth / 2, 0.0);
  const Vec3 margin = Vec3::Constant(0.5 * setup.thickness);
  setup.simulator->add_obstacle(box_obstacle(lower - margin, upper + margin, p.at("friction")));
  setup.objects.push_back(cloth_object("cloth", cloth, first));
  if (shape_obstacles(p)) {
    // Centre and half extents are exact here (halves of the table's sizes), so the box's corners are the mesh's.
    const Vec3 centre = 0.5 * (lower + upper), half = 0.5 * (upper - lower);
    setup.objects.push_back(shape_object(
        "table", box_shape(half), [centre](double) { return centre; }, true));
  } else {
    setup.objects.push_back(static_object("table", box(lower, upper)));
  }
  setup.collidable = {{"cloth", "table"}};
  setup.report = [width, depth](std::size_t, double, const std::vector<std::vector<Vec3>>& x) {
    double lowest = std::numeric_limits<double>::infinity();
    std::size_t on_top = 0;
    for (const Vec3& v : x[0]) {
      lowest = std::min(lowest, v.z());
      if (std::abs(v.x()) < width / 2 && std::abs(v.y()) < depth / 2 && v.z() < 0.01) ++on_top;
    }
    return Metrics{{"lowest_z", lowest}, {"vertices_on_table", static_cast<double>(on_top)}};
  };
  return setup;
}

}  // namespace

SceneDefinition drape_scene() {
  return {{"drape", "cloth falls on a table and drapes over its edges",
           with_common({{"table_width", 1.0, "table size along x (m); the cloth is 1.4 times as wide"},
                        {"table_depth", 0.7, "table size along y (m)"},
                        {"friction", 0.6, "cloth-table friction"},
                        kObstaclesParameter})},
          drape};
}

}  // namespace ccd::datasets::procedural
