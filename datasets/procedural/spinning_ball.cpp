#include "datasets/procedural/obstacles.hpp"
#include "datasets/procedural/scene_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ccd::datasets::procedural {
namespace {

Setup spinning_ball(CommonParameters& c, const SceneParameters& p) {
  const double radius = p.at("radius"), spin = p.at("spin"), spin_start = p.at("spin_start");
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double angle = unit(c.random) * std::numbers::pi / 2;
  const Vec3 offset((unit(c.random) - 0.5) * 0.1 * radius, (unit(c.random) - 0.5) * 0.1 * radius, radius + p.at("drop"));
  const ShapeMesh cloth = placed_cloth(c.n, 3.2 * radius, angle, offset);
  Setup setup;
  setup.thickness = thickness_of(cloth);
  setup.simulator = std::make_unique<ClothSimulator>(settings_for(cloth, c.n));
  const std::size_t first = setup.simulator->add_cloth(c.n, cloth.positions);
  auto omega = [spin, spin_start](double t) { return t >= spin_start ? spin : 0.0; };
  auto turned = [spin, spin_start](double t) { return spin * std::max(0.0, t - spin_start); };
  // Cloth rests half a thickness off the analytic sphere, inside δ of the ball mesh near its vertices.
  setup.simulator->add_obstacle(sphere_obstacle(radius + 0.5 * setup.thickness, p.at("friction"), omega));
  setup.objects.push_back(cloth_object("cloth", cloth, first));
  const ShapeMesh ball = uv_sphere(radius, 24, 48);
  if (shape_obstacles(p)) {
    // The sphere's spin leaves it unchanged: a still centre at the origin.
    setup.objects.push_back(shape_object(
        "ball", sphere_shape(radius), [](double) { return Vec3::Zero().eval(); }, true));
  } else
    setup.objects.push_back(
        {"ball", ObjectKind::rigid, false, ball.faces, ball.positions.size(), [base = ball.positions, turned](const ClothSimulator&, double t) {
           std::vector<Vec3> x(base.size());
           for (std::size_t i = 0; i < base.size(); ++i) x[i] = rotate_z(base[i], turned(t));
           return x;
         }});
  setup.collidable = {{"cloth", "ball"}};
  setup.report = [radius, turned, initial = std::vector<Vec3>()](std::size_t frame, double t, const std::vector<std::vector<Vec3>>& x) mutable {
    const auto& cloth_x = x[0];
    if (frame == 0) initial = cloth_x;
    double nearest = std::numeric_limits<double>::infinity(), rotation = 0.0;
    std::size_t counted = 0;
    for (std::size_t i = 0; i < cloth_x.size(); ++i) {
      nearest = std::min(nearest, cloth_x[i].norm() - radius);
      if (std::hypot(initial[i].x(), initial[i].y()) < 0.25 * radius || std::hypot(cloth_x[i].x(), cloth_x[i].y()) < 0.25 * radius) continue;
      rotation += wrapped(std::atan2(cloth_x[i].y(), cloth_x[i].x()) - std::atan2(initial[i].y(), initial[i].x()));
      ++counted;
    }
    return Metrics{{"min_distance_to_ball", nearest},
                   {"cloth_rotation_deg", counted ? rotation / static_cast<double>(counted) * 180 / std::numbers::pi : 0.0},
                   {"ball_rotation_deg", turned(t) * 180 / std::numbers::pi}};
  };
  return setup;
}

}  // namespace

SceneDefinition spinning_ball_scene() {
  return {{"spinning-ball", "cloth falls on a sphere that then spins and wraps it (the paper's benchmark)",
           with_common({{"radius", 0.5, "ball radius (m); the cloth is 3.2 radii wide"},
                        {"spin", 3.0, "ball angular speed about z once spinning (rad/s)"},
                        {"spin_start", 0.3, "time the ball starts spinning (s)"},
                        {"drop", 0.02, "initial gap between cloth and ball top (m)"},
                        {"friction", 0.9, "cloth-ball friction (0 slides, 1 sticks)"},
                        kObstaclesParameter})},
          spinning_ball};
}

}  // namespace ccd::datasets::procedural
