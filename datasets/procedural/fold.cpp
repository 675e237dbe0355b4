#include "datasets/procedural/obstacles.hpp"
#include "datasets/procedural/scene_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace ccd::datasets::procedural {
namespace {

/// Kinematic: no simulation, every vertex follows a formula of time, so the scene makes what the simulator never
/// does (it keeps cloth about δ/2 off everything): real crossings, for gates and tests at δ = 0. A sheet folds its
/// right part over and then through its left part. The fold curls (the far edge turns `curl` degrees ahead of the
/// hinge), so the contact front sweeps from the far edge towards the hinge over many frames rather than landing in
/// one step. Meanwhile a rigid blade cuts down through the left part: contact between objects. Per frame, nothing
/// moves more than a fraction of an edge, so apccd's sessions last several frames and find contacts inside them.
Setup fold(CommonParameters& c, const SceneParameters& p) {
  const double size = 1.0, spacing = size / static_cast<double>(c.n - 1);
  const double degree = std::numbers::pi / 180.0;
  const double start = p.at("fold_start") * degree, end = p.at("fold_end") * degree, curl = p.at("curl") * degree;
  const double travel = p.at("blade_travel");
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  ShapeMesh sheet = cloth_grid(c.n, size);
  // A seeded ripple of 1e-3 of an edge keeps the crossings transversal (no exactly coplanar landing).
  for (Vec3& v : sheet.positions) v.z() = 1e-3 * spacing * (unit(c.random) - 0.5);
  const double hinge = sheet.positions[c.n / 2].x(), reach = sheet.positions[c.n - 1].x() - hinge;
  const double last_time = static_cast<double>(c.frames - 1) * SimulatorSettings{}.frame_seconds;
  auto fold_angle = [=](double t) { return start + (end - start) * t / last_time; };
  Setup setup;
  setup.thickness = thickness_of(sheet);
  setup.simulator = std::make_unique<ClothSimulator>(SimulatorSettings{});  // nothing to simulate
  setup.objects.push_back({"sheet", ObjectKind::deformable, true, sheet.faces, sheet.positions.size(),
                           [rest = sheet.positions, hinge, reach, curl, fold_angle](const ClothSimulator&, double t) {
                             std::vector<Vec3> x = rest;
                             for (Vec3& v : x) {
                               const double d = v.x() - hinge;
                               if (d <= 0) continue;
                               const double angle = fold_angle(t) + curl * d / reach;
                               v = Vec3(hinge + d * std::cos(angle), v.y(), v.z() + d * std::sin(angle));
                             }
                             return x;
                           }});
  // The blade: a vertical 3x3 plate across the left part, between two rows of the sheet, moving down by `travel`
  // so that it passes the sheet's plane half-way through the frames.
  const double row = std::floor(static_cast<double>(c.n) / 4.0);
  const double blade_y = -0.5 + spacing * (row + 0.37), blade_x = -0.5 + 0.3 * (hinge + 0.5);
  const double width = 0.4 * (hinge + 0.5), height = 0.3;
  const ShapeMesh plate = cloth_grid(3, 1.0);
  if (shape_obstacles(p)) {
    // The blade as a thin box around the same plate, and a ball driven down through the left part's other half:
    // face-shape contacts of both kinds at δ = 0.
    const Vec3 half(width / 2, 0.1 * spacing, height / 2);
    setup.objects.push_back(shape_object(
        "blade", box_shape(half), [=](double t) { return Vec3(blade_x + width / 2, blade_y, travel * (0.5 - t / last_time)); }, false));
    const double ball_radius = 0.15 * (hinge + 0.5), ball_x = -0.5 + 0.5 * (hinge + 0.5), ball_y = 0.25;
    setup.objects.push_back(shape_object(
        "ball", sphere_shape(ball_radius), [=](double t) { return Vec3(ball_x, ball_y, (travel + 2 * ball_radius) * (0.5 - t / last_time)); },
        false));
    setup.collidable = {{"sheet", "blade"}, {"sheet", "ball"}};
  } else
    setup.objects.push_back({"blade", ObjectKind::rigid, false, plate.faces, plate.positions.size(),
                             [plate = plate.positions, blade_x, blade_y, width, height, travel, last_time](const ClothSimulator&, double t) {
                               const double centre = travel * (0.5 - t / last_time);
                               std::vector<Vec3> x;
                               for (const Vec3& q : plate) x.emplace_back(blade_x + (q.x() + 0.5) * width, blade_y, centre + q.y() * height);
                               return x;
                             }});
  if (!shape_obstacles(p)) setup.collidable = {{"sheet", "blade"}};
  setup.report = [fold_angle, travel, last_time](std::size_t, double t, const std::vector<std::vector<Vec3>>&) {
    return Metrics{{"fold_angle_deg", fold_angle(t) * 180 / std::numbers::pi}, {"blade_centre_z", travel * (0.5 - t / last_time)}};
  };
  return setup;
}

}  // namespace

SceneDefinition fold_scene() {
  return {{"fold", "kinematic: a sheet folds over and through itself while a blade cuts through it (real crossings)",
           with_common({{"fold_start", 140, "fold angle at the first frame (degrees; 180 lays the part flat on the rest)"},
                        {"fold_end", 200, "fold angle at the last frame (degrees)"},
                        {"curl", 30, "how far the far edge turns ahead of the hinge (degrees)"},
                        {"blade_travel", 0.5, "how far the blade moves down over the frames (m)"},
                        kObstaclesParameter})},
          fold};
}

}  // namespace ccd::datasets::procedural
