#include "datasets/procedural_scenes.hpp"

#include "core/error.hpp"
#include "core/scene.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/cloth_simulator.hpp"
#include "datasets/frame_cache.hpp"
#include "datasets/ply.hpp"
#include "datasets/scene_file.hpp"
#include "datasets/shapes.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <unistd.h>

namespace ccd::datasets {
namespace {

/// Bumped whenever the simulator or a scene changes what it generates, so old caches are not reused.
constexpr int kGeneratorVersion = 3;

// ---------------------------------------------------------------------------------------------------------------
// Obstacles: analytic shapes for the simulator (their meshes are what the strategies see).

/// Removes the motion of a projected particle relative to the surface, tangentially, by `friction` (1 sticks).
void apply_friction(Vec3& q, const Vec3& previous, const Vec3& normal, const Vec3& surface_velocity, double dt,
                    double friction) {
  const Vec3 relative = (q - previous) - surface_velocity * dt;
  q -= friction * (relative - relative.dot(normal) * normal);
}

/// A sphere at the origin spinning about z with angular speed omega(time).
class SphereObstacle final : public Obstacle {
 public:
  SphereObstacle(double radius, double friction, std::function<double(double)> omega)
      : radius_(radius), friction_(friction), omega_(std::move(omega)) {}
  void project(Vec3& p, const Vec3& previous, double time, double dt) const override {
    const double distance = p.norm();
    if (distance >= radius_) return;
    const Vec3 normal = distance > 0 ? Vec3(p / distance) : Vec3(0, 0, 1);
    p = radius_ * normal;
    apply_friction(p, previous, normal, omega_(time) * Vec3(0, 0, 1).cross(p), dt, friction_);
  }

 private:
  double radius_, friction_;
  std::function<double(double)> omega_;
};

class PlaneObstacle final : public Obstacle {
 public:
  PlaneObstacle(double height, double friction) : height_(height), friction_(friction) {}
  void project(Vec3& p, const Vec3& previous, double, double dt) const override {
    if (p.z() >= height_) return;
    p.z() = height_;
    apply_friction(p, previous, Vec3(0, 0, 1), Vec3(0, 0, 0), dt, friction_);
  }

 private:
  double height_, friction_;
};

class BoxObstacle final : public Obstacle {
 public:
  BoxObstacle(const Vec3& lower, const Vec3& upper, double friction) : lower_(lower), upper_(upper), friction_(friction) {}
  void project(Vec3& p, const Vec3& previous, double, double dt) const override {
    for (int k = 0; k < 3; ++k) {
      if (p[k] <= lower_[k] || p[k] >= upper_[k]) return;
    }
    // Leave through the nearest side.
    int best_axis = 0;
    double best_depth = std::numeric_limits<double>::infinity(), best_target = 0, best_sign = 0;
    for (int k = 0; k < 3; ++k) {
      for (double sign : {-1.0, 1.0}) {
        const double target = sign < 0 ? lower_[k] : upper_[k];
        const double depth = std::abs(target - p[k]);
        if (depth < best_depth) {
          best_depth = depth;
          best_axis = k;
          best_target = target;
          best_sign = sign;
        }
      }
    }
    p[best_axis] = best_target;
    Vec3 normal(0, 0, 0);
    normal[best_axis] = best_sign;
    apply_friction(p, previous, normal, Vec3(0, 0, 0), dt, friction_);
  }

 private:
  Vec3 lower_, upper_;
  double friction_;
};

/// The inside of a funnel around z: between z_bottom and z_top a particle stays within the radius there.
class FunnelObstacle final : public Obstacle {
 public:
  FunnelObstacle(double r_bottom, double z_bottom, double r_top, double z_top, double friction)
      : r_bottom_(r_bottom), z_bottom_(z_bottom), r_top_(r_top), z_top_(z_top), friction_(friction) {}
  void project(Vec3& p, const Vec3& previous, double, double dt) const override {
    if (p.z() < z_bottom_ || p.z() > z_top_) return;
    const double allowed = r_bottom_ + (p.z() - z_bottom_) * (r_top_ - r_bottom_) / (z_top_ - z_bottom_);
    const double radial = std::hypot(p.x(), p.y());
    if (radial <= allowed) return;
    const Vec3 outward(p.x() / radial, p.y() / radial, 0.0);
    p.x() *= allowed / radial;
    p.y() *= allowed / radial;
    apply_friction(p, previous, -outward, Vec3(0, 0, 0), dt, friction_);
  }

 private:
  double r_bottom_, z_bottom_, r_top_, z_top_, friction_;
};

// ---------------------------------------------------------------------------------------------------------------
// Scenes.

struct OutputObject {
  std::string name;
  ObjectKind kind;
  bool self_collision;
  std::vector<Face> faces;
  std::size_t num_vertices;
  /// Positions at `time`: a slice of the simulator for cloths, a function of time for obstacles (a shape's centre).
  std::function<std::vector<Vec3>(const ClothSimulator&, double)> positions;
  /// Kind shape only: the obstacle's size, and whether its centre never moves (then one frame is kept).
  std::optional<Shape> shape = std::nullopt;
  bool still = false;
};

using Metrics = std::vector<std::pair<std::string, double>>;

struct Setup {
  std::unique_ptr<ClothSimulator> simulator;
  std::vector<OutputObject> objects;
  std::vector<std::pair<std::string, std::string>> collidable;
  double thickness = 0.0;
  /// Scene-specific measurements of one frame from every object's positions (works on cached frames too).
  std::function<Metrics(std::size_t frame, double time, const std::vector<std::vector<Vec3>>& objects)> report;
};

struct CommonParameters {
  std::size_t n;
  /// Simulated frames (30 per simulated second).
  std::size_t frames;
  std::mt19937_64 random;
  /// CCD steps per simulated frame: the emitted frames are (frames - 1) · steps_per_frame + 1.
  std::size_t steps_per_frame = 1;
};

Vec3 rotate_z(const Vec3& p, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * p.x() - s * p.y(), s * p.x() + c * p.y(), p.z()};
}

double mean_edge_length(const ShapeMesh& mesh) {
  const MeshTopology topology(mesh.positions.size(), mesh.faces);
  double sum = 0.0;
  for (const Edge& e : topology.edges()) sum += (mesh.positions[e.v0] - mesh.positions[e.v1]).norm();
  return sum / static_cast<double>(topology.num_edges());
}

/// DESIGN.md §1: built-in scenes declare δ as 5% of the cloth's mean rest edge length.
double thickness_of(const ShapeMesh& cloth) { return 0.05 * mean_edge_length(cloth); }

SimulatorSettings settings_for(const ShapeMesh& cloth, std::size_t n) {
  SimulatorSettings settings;
  const double spacing = (cloth.positions[1] - cloth.positions[0]).norm();
  settings.repulsion_radius = 0.6 * spacing;
  // Finer cloth needs more constraint sweeps to stay as stiff; a few more per doubling of the side.
  settings.iterations = 4 + static_cast<int>(std::log2(static_cast<double>(n)));
  return settings;
}

OutputObject cloth_object(std::string name, const ShapeMesh& mesh, std::size_t first) {
  const std::size_t count = mesh.positions.size();
  return {std::move(name), ObjectKind::deformable, true, mesh.faces, count,
          [first, count](const ClothSimulator& simulator, double) {
            const auto& x = simulator.positions();
            return std::vector<Vec3>(x.begin() + static_cast<std::ptrdiff_t>(first),
                                     x.begin() + static_cast<std::ptrdiff_t>(first + count));
          }};
}

OutputObject static_object(std::string name, ShapeMesh mesh) {
  const std::size_t count = mesh.positions.size();
  auto positions = mesh.positions;
  return {std::move(name), ObjectKind::static_object, false, std::move(mesh.faces), count,
          [positions](const ClothSimulator&, double) { return positions; }};
}

/// An analytic obstacle (obstacles=shape): one vertex, its centre, at `centre(t)`.
OutputObject shape_object(std::string name, Shape shape, std::function<Vec3(double)> centre, bool still) {
  return {std::move(name), ObjectKind::shape, false, {}, 1,
          [centre = std::move(centre)](const ClothSimulator&, double t) { return std::vector<Vec3>{centre(t)}; },
          shape, still};
}

Shape sphere_shape(double radius) { return {ShapeKind::sphere, radius, Vec3::Zero()}; }
Shape box_shape(const Vec3& half_extents) { return {ShapeKind::box, 0.0, half_extents}; }

/// obstacles=shape (1) or mesh (0, the default).
bool shape_obstacles(const SceneParameters& p) { return p.at("obstacles") == 1.0; }

/// Cloth grid of side `size`, rotated about z by `angle`, moved by `offset`.
ShapeMesh placed_cloth(std::size_t n, double size, double angle, const Vec3& offset) {
  ShapeMesh cloth = cloth_grid(n, size);
  for (Vec3& p : cloth.positions) p = rotate_z(p, angle) + offset;
  return cloth;
}

double wrapped(double angle) { return std::remainder(angle, 2 * std::numbers::pi); }

Setup spinning_ball(CommonParameters& c, const SceneParameters& p) {
  const double radius = p.at("radius"), spin = p.at("spin"), spin_start = p.at("spin_start");
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double angle = unit(c.random) * std::numbers::pi / 2;
  const Vec3 offset((unit(c.random) - 0.5) * 0.1 * radius, (unit(c.random) - 0.5) * 0.1 * radius,
                    radius + p.at("drop"));
  const ShapeMesh cloth = placed_cloth(c.n, 3.2 * radius, angle, offset);
  Setup setup;
  setup.thickness = thickness_of(cloth);
  setup.simulator = std::make_unique<ClothSimulator>(settings_for(cloth, c.n));
  const std::size_t first = setup.simulator->add_cloth(c.n, cloth.positions);
  auto omega = [spin, spin_start](double t) { return t >= spin_start ? spin : 0.0; };
  auto turned = [spin, spin_start](double t) { return spin * std::max(0.0, t - spin_start); };
  // Cloth rests half a thickness off the analytic sphere, inside δ of the ball mesh near its vertices.
  setup.simulator->add_obstacle(std::make_shared<SphereObstacle>(radius + 0.5 * setup.thickness, p.at("friction"), omega));
  setup.objects.push_back(cloth_object("cloth", cloth, first));
  const ShapeMesh ball = uv_sphere(radius, 24, 48);
  if (shape_obstacles(p)) {
    // The sphere's spin leaves it unchanged: a still centre at the origin.
    setup.objects.push_back(shape_object("ball", sphere_shape(radius), [](double) { return Vec3::Zero().eval(); }, true));
  } else setup.objects.push_back({"ball", ObjectKind::rigid, false, ball.faces, ball.positions.size(),
                           [base = ball.positions, turned](const ClothSimulator&, double t) {
                             std::vector<Vec3> x(base.size());
                             for (std::size_t i = 0; i < base.size(); ++i) x[i] = rotate_z(base[i], turned(t));
                             return x;
                           }});
  setup.collidable = {{"cloth", "ball"}};
  setup.report = [radius, turned, initial = std::vector<Vec3>()](std::size_t frame, double t,
                                                                  const std::vector<std::vector<Vec3>>& x) mutable {
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

Setup drape(CommonParameters& c, const SceneParameters& p) {
  const double width = p.at("table_width"), depth = p.at("table_depth");
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const ShapeMesh cloth = placed_cloth(c.n, 1.4 * width, (unit(c.random) - 0.5) * 0.3,
                                       Vec3((unit(c.random) - 0.5) * 0.1, (unit(c.random) - 0.5) * 0.1, 0.1));
  Setup setup;
  setup.thickness = thickness_of(cloth);
  setup.simulator = std::make_unique<ClothSimulator>(settings_for(cloth, c.n));
  const std::size_t first = setup.simulator->add_cloth(c.n, cloth.positions);
  const Vec3 lower(-width / 2, -depth / 2, -0.75), upper(width / 2, depth / 2, 0.0);
  const Vec3 margin = Vec3::Constant(0.5 * setup.thickness);
  setup.simulator->add_obstacle(std::make_shared<BoxObstacle>(lower - margin, upper + margin, p.at("friction")));
  setup.objects.push_back(cloth_object("cloth", cloth, first));
  if (shape_obstacles(p)) {
    // Centre and half extents are exact here (halves of the table's sizes), so the box's corners are the mesh's.
    const Vec3 centre = 0.5 * (lower + upper), half = 0.5 * (upper - lower);
    setup.objects.push_back(shape_object("table", box_shape(half), [centre](double) { return centre; }, true));
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

Setup flag(CommonParameters& c, const SceneParameters& p) {
  const double size = 1.0;
  ShapeMesh cloth = cloth_grid(c.n, size);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double spacing = size / static_cast<double>(c.n - 1);
  for (std::size_t i = 0; i < c.n; ++i) {
    for (std::size_t j = 0; j < c.n; ++j) {
      // Hung in the x-z plane from the pole at x = 0; a tiny seeded ripple breaks the symmetry.
      cloth.positions[i * c.n + j] = Vec3(static_cast<double>(j) * spacing, 1e-3 * spacing * (unit(c.random) - 0.5),
                                          1.5 - static_cast<double>(i) * spacing);
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
      if (k % n == 0) drift = std::max(drift, (x[0][k] - initial[k]).norm());
      else moved += (x[0][k] - initial[k]).norm();
    }
    return Metrics{{"pinned_drift", drift}, {"mean_free_displacement", moved / static_cast<double>(x[0].size() - n)}};
  };
  return setup;
}

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
        return Vec3(x, rest.y() * std::cos(angle) - rest.z() * std::sin(angle),
                    rest.y() * std::sin(angle) + rest.z() * std::cos(angle));
      });
    }
  }
  setup.objects.push_back(cloth_object("mat", cloth, first));
  setup.report = [rate](std::size_t, double t, const std::vector<std::vector<Vec3>>&) {
    return Metrics{{"clamp_angle_deg", 2 * rate * t * 180 / std::numbers::pi}};
  };
  return setup;
}

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
  setup.simulator->add_obstacle(std::make_shared<FunnelObstacle>(r_bottom - 0.5 * setup.thickness, z_bottom,
                                                                 r_top - 0.5 * setup.thickness, z_top, p.at("friction")));
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
  setup.simulator->add_obstacle(std::make_shared<PlaneObstacle>(0.5 * setup.thickness, p.at("friction")));
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t first = setup.simulator->add_cloth(c.n, cloths[k].positions);
    setup.objects.push_back(cloth_object("cloth" + std::to_string(k), cloths[k], first));
  }
  if (shape_obstacles(p)) {
    // A thin box under the ground plane whose top face is the ground mesh's square: its centre and half extents
    // are powers of two, so the top face lies exactly at z = 0.
    const Vec3 half(1.5, 1.5, kGroundBoxHalfThickness), centre(0, 0, -kGroundBoxHalfThickness);
    setup.objects.push_back(shape_object("ground", box_shape(half), [centre](double) { return centre; }, true));
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
    setup.objects.push_back(shape_object("blade", box_shape(half), [=](double t) {
      return Vec3(blade_x + width / 2, blade_y, travel * (0.5 - t / last_time));
    }, false));
    const double ball_radius = 0.15 * (hinge + 0.5), ball_x = -0.5 + 0.5 * (hinge + 0.5), ball_y = 0.25;
    setup.objects.push_back(shape_object("ball", sphere_shape(ball_radius), [=](double t) {
      return Vec3(ball_x, ball_y, (travel + 2 * ball_radius) * (0.5 - t / last_time));
    }, false));
    setup.collidable = {{"sheet", "blade"}, {"sheet", "ball"}};
  } else setup.objects.push_back({"blade", ObjectKind::rigid, false, plate.faces, plate.positions.size(),
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

struct SceneDefinition {
  ProceduralSceneInfo info;
  Setup (*build)(CommonParameters&, const SceneParameters&);
};

std::vector<SceneParameter> with_common(std::vector<SceneParameter> own) {
  std::vector<SceneParameter> all = {{"resolution", 32, "cloth grid side N: N x N vertices, 2(N-1)^2 triangles per cloth"},
                                     {"frames", 30, "frames to generate (steps = frames - 1), 30 per simulated second"},
                                     {"seed", 1, "seed of the scene's random placement and gusts"},
                                     {"steps_per_frame", 1,
                                      "CCD steps per simulated frame: the simulator's substeps emitted as steps, simulated time "
                                      "and motion unchanged ((frames - 1) x this + 1 frames are written; 1, 2 and 4 keep the "
                                      "simulator's 4 substeps per frame bit for bit, others the next multiple)"}};
  all.insert(all.end(), own.begin(), own.end());
  return all;
}

/// Obstacles as triangle meshes (the paper's) or as analytic shapes (core/shape.hpp).
const SceneParameter kObstaclesParameter{"obstacles", 0, "mesh or shape: obstacles as triangle meshes or as analytic shapes (a sphere, a box)",
                                         {"mesh", "shape"}};

const std::vector<SceneDefinition>& definitions() {
  static const std::vector<SceneDefinition> scenes = {
      {{"spinning-ball", "cloth falls on a sphere that then spins and wraps it (the paper's benchmark)",
        with_common({{"radius", 0.5, "ball radius (m); the cloth is 3.2 radii wide"},
                     {"spin", 3.0, "ball angular speed about z once spinning (rad/s)"},
                     {"spin_start", 0.3, "time the ball starts spinning (s)"},
                     {"drop", 0.02, "initial gap between cloth and ball top (m)"},
                     {"friction", 0.9, "cloth-ball friction (0 slides, 1 sticks)"},
                     kObstaclesParameter})},
       spinning_ball},
      {{"drape", "cloth falls on a table and drapes over its edges",
        with_common({{"table_width", 1.0, "table size along x (m); the cloth is 1.4 times as wide"},
                     {"table_depth", 0.7, "table size along y (m)"},
                     {"friction", 0.6, "cloth-table friction"},
                     kObstaclesParameter})},
       drape},
      {{"flag", "cloth pinned along one side, blown by gusty wind",
        with_common({{"wind", 8.0, "mean wind speed along +x (m/s)"}})},
       flag},
      {{"twist", "a mat whose two ends turn in opposite directions and close in: heavy self-contact",
        with_common({{"twist_rate", 2.5, "each clamp's angular speed about x (rad/s)"},
                     {"squeeze", 0.35, "fraction by which the clamps close in over the first second"}})},
       twist},
      {{"funnel", "cloth pulled by its centre down through a funnel",
        with_common({{"pull_speed", 0.6, "downward speed of the pulled centre (m/s)"},
                     {"friction", 0.3, "cloth-funnel friction"}})},
       funnel},
      {{"pile", "several cloths fall on the ground and on each other: inter-object contact",
        with_common({{"count", 3, "number of cloths"}, {"friction", 0.5, "cloth-ground friction"}, kObstaclesParameter})},
       pile},
      {{"fold", "kinematic: a sheet folds over and through itself while a blade cuts through it (real crossings)",
        with_common({{"fold_start", 140, "fold angle at the first frame (degrees; 180 lays the part flat on the rest)"},
                     {"fold_end", 200, "fold angle at the last frame (degrees)"},
                     {"curl", 30, "how far the far edge turns ahead of the hinge (degrees)"},
                     {"blade_travel", 0.5, "how far the blade moves down over the frames (m)"},
                     kObstaclesParameter})},
       fold},
  };
  return scenes;
}

const SceneDefinition& find_definition(const std::string& name) {
  for (const SceneDefinition& d : definitions()) {
    if (d.info.name == name) return d;
  }
  std::string known;
  for (const SceneDefinition& d : definitions()) known += (known.empty() ? "" : ", ") + d.info.name;
  throw std::invalid_argument("unknown scene '" + name + "' (built-in: " + known + ")");
}

SceneParameters resolve_parameters(const ProceduralSceneInfo& info, const SceneParameters& given) {
  SceneParameters resolved;
  for (const SceneParameter& parameter : info.parameters) resolved[parameter.name] = parameter.default_value;
  for (const auto& [name, value] : given) {
    if (!resolved.count(name)) {
      std::string known;
      for (const SceneParameter& parameter : info.parameters) known += (known.empty() ? "" : ", ") + parameter.name;
      throw std::invalid_argument("scene '" + info.name + "' has no parameter '" + name + "' (it has: " + known + ")");
    }
    if (!std::isfinite(value)) throw std::invalid_argument("parameter '" + name + "' must be finite");
    resolved[name] = value;
  }
  auto require_integer = [&](const char* name, double low, double high) {
    const double value = resolved.at(name);
    if (value != std::floor(value) || value < low || value > high) {
      std::ostringstream message;
      message << "parameter '" << name << "' must be an integer in [" << low << ", " << high << "], got " << value;
      throw std::invalid_argument(message.str());
    }
  };
  require_integer("resolution", 3, 4096);
  require_integer("frames", 2, 100000);
  require_integer("seed", 0, 9007199254740992.0);
  require_integer("steps_per_frame", 1, 64);
  for (const SceneParameter& parameter : info.parameters) {
    if (!parameter.choices.empty()) require_integer(parameter.name.c_str(), 0, static_cast<double>(parameter.choices.size() - 1));
  }
  if (resolved.count("count")) require_integer("count", 1, 64);
  return resolved;
}

/// "wind=1e+06 (default 8), frames=400 (default 30)": the parameters a user changed, for messages.
std::string changed_parameters(const ProceduralSceneInfo& info, const SceneParameters& parameters) {
  std::ostringstream text;
  for (const SceneParameter& parameter : info.parameters) {
    const double value = parameters.at(parameter.name);
    if (value == parameter.default_value) continue;
    text << (text.tellp() > 0 ? ", " : "") << parameter.name << "=" << value << " (default " << parameter.default_value << ")";
  }
  return text.tellp() > 0 ? text.str() : "every parameter at its default";
}

/// Refuses, before anything is allocated, a scene whose simulation would not fit this machine's memory or whose
/// frames would not fit the output's disk (resolution 4096 with 64 cloths would otherwise end in std::bad_alloc).
/// The simulator keeps about kSimulatorBytesPerVertex per cloth vertex (positions, velocities, constraints and
/// their colour groups, repulsion cells); each frame is written twice (cache and PLY), 24 bytes per vertex each.
void check_scene_fits(const ProceduralSceneInfo& info, const SceneParameters& parameters, const std::filesystem::path& out) {
  constexpr double kSimulatorBytesPerVertex = 1024;
  constexpr double kFrameBytesPerVertex = 2 * 3 * sizeof(double);
  const double n = parameters.at("resolution");
  const double cloths = parameters.count("count") ? parameters.at("count") : 1.0;
  const double vertices = n * n * cloths;
  const double memory = static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
  constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
  std::ostringstream message;
  message << std::setprecision(3);
  if (memory > 0 && vertices * kSimulatorBytesPerVertex > memory) {
    message << "scene '" << info.name << "' with " << changed_parameters(info, parameters) << " needs about "
            << vertices * kSimulatorBytesPerVertex / kGiB << " GiB to simulate; this machine has " << memory / kGiB << " GiB";
    throw std::invalid_argument(message.str());
  }
  std::error_code error;
  std::filesystem::path existing = out;
  while (!existing.empty() && !std::filesystem::exists(existing, error)) existing = existing.parent_path();
  const auto space = std::filesystem::space(existing.empty() ? std::filesystem::path(".") : existing, error);
  const double frame_bytes = vertices * kFrameBytesPerVertex * parameters.at("frames");
  if (!error && frame_bytes > static_cast<double>(space.available)) {
    message << "scene '" << info.name << "' with " << changed_parameters(info, parameters) << " needs about "
            << frame_bytes / kGiB << " GiB for its frames; " << out.string() << " has " << static_cast<double>(space.available) / kGiB
            << " GiB free";
    throw std::invalid_argument(message.str());
  }
}

std::string cache_key(const std::string& name, const SceneParameters& parameters) {
  std::ostringstream key;
  key << "ccdbench procedural v" << kGeneratorVersion << ' ' << name << std::setprecision(17);
  for (const auto& [parameter, value] : parameters) {
    // steps_per_frame=1 (the default) is left out, so that the scenes generated before it existed keep their key.
    if (parameter == "steps_per_frame" && value == 1) continue;
    if (parameter == "obstacles" && value == 0) continue;  // likewise obstacles=mesh
    key << ' ' << parameter << '=' << value;
  }
  return key.str();
}

std::filesystem::path frame_file(const std::filesystem::path& out, const std::string& object, std::size_t frame) {
  std::ostringstream name;
  name << "frame_" << std::setw(4) << std::setfill('0') << frame << ".ply";
  return out / object / name.str();
}

std::size_t frames_of(const OutputObject& object, std::size_t frames) {
  return object.kind == ObjectKind::static_object || object.still ? 1 : frames;
}

void write_scene_json(const std::filesystem::path& out, const std::string& name, const Setup& setup) {
  nlohmann::json objects = nlohmann::json::array();
  for (const OutputObject& object : setup.objects) {
    if (object.shape) {
      nlohmann::json entry = {{"name", object.name}, {"kind", "shape"}, {"track", {{"cache", "cache/" + object.name + ".frames"}}}};
      put_shape_keys(entry, *object.shape);
      objects.push_back(entry);
      continue;
    }
    nlohmann::json frames = object.kind == ObjectKind::static_object
                                ? nlohmann::json{{"files", {object.name + "/frame_0000.ply"}}}
                                : nlohmann::json{{"pattern", object.name + "/frame_%04d.ply"}};
    objects.push_back({{"name", object.name},
                       {"kind", std::string(to_string(object.kind))},
                       {"self_collision", object.self_collision},
                       {"frames", frames}});
  }
  nlohmann::json collidable = nlohmann::json::array();
  for (const auto& [a, b] : setup.collidable) collidable.push_back({a, b});
  const nlohmann::json document = {{"name", name}, {"thickness", setup.thickness}, {"objects", objects},
                                   {"collidable", collidable}};
  AtomicFile file(out / "scene.json", std::ios::out);
  file.stream() << document.dump(2) << '\n';
  file.commit();
}

/// Whether `out` holds this generation whole: caches with the key, every PLY, and scene.json (written last).
bool complete_in(const std::filesystem::path& out, const Setup& setup, const std::string& key, std::size_t frames) {
  if (!std::filesystem::exists(out / "scene.json")) return false;
  for (const OutputObject& object : setup.objects) {
    try {
      if (!open_frame_cache(out / "cache" / (object.name + ".frames"), key)) return false;
    } catch (const InputError& corrupt) {
      // A corrupt or old cache is never used: the scene is generated again over it.
      std::cerr << "ccdbench: warning: " << corrupt.what() << "; the scene is generated again\n";
      return false;
    }
    const std::size_t count = frames_of(object, frames);
    if (object.shape) continue;  // a shape's track is its cache; it has no PLY frames
    if (!std::filesystem::exists(frame_file(out, object.name, count - 1)) ||
        std::filesystem::exists(frame_file(out, object.name, count))) {
      return false;
    }
  }
  return true;
}

}  // namespace

const std::vector<ProceduralSceneInfo>& procedural_scenes() {
  static const std::vector<ProceduralSceneInfo> infos = [] {
    std::vector<ProceduralSceneInfo> result;
    for (const SceneDefinition& d : definitions()) result.push_back(d.info);
    return result;
  }();
  return infos;
}

std::optional<double> scene_parameter_choice(const std::string& scene, const std::string& parameter, const std::string& text) {
  for (const SceneParameter& p : find_definition(scene).info.parameters) {
    if (p.name != parameter) continue;
    for (std::size_t i = 0; i < p.choices.size(); ++i) {
      if (p.choices[i] == text) return static_cast<double>(i);
    }
  }
  return std::nullopt;
}

SceneParameters resolve_scene_parameters(const std::string& name, const SceneParameters& given) {
  return resolve_parameters(find_definition(name).info, given);
}

GenerateResult generate_procedural_scene(const GenerateRequest& request) {
  const auto start = std::chrono::steady_clock::now();
  const SceneDefinition& definition = find_definition(request.name);
  const SceneParameters parameters = resolve_parameters(definition.info, request.parameters);
  check_scene_fits(definition.info, parameters, request.out);
  CommonParameters common{static_cast<std::size_t>(parameters.at("resolution")),
                          static_cast<std::size_t>(parameters.at("frames")),
                          std::mt19937_64(static_cast<std::uint64_t>(parameters.at("seed"))),
                          static_cast<std::size_t>(parameters.at("steps_per_frame"))};
  Setup setup = definition.build(common, parameters);
  const std::string key = cache_key(request.name, parameters);
  // Every CCD step is 1/steps_per_frame of a simulated frame; the emitted frames are the simulator's states at
  // those times.
  const std::size_t parts = common.steps_per_frame;
  const std::size_t emitted = (common.frames - 1) * parts + 1;
  const double frame_seconds = SimulatorSettings{}.frame_seconds;
  auto time_of = [&](std::size_t frame) { return static_cast<double>(frame) * frame_seconds / static_cast<double>(parts); };
  // One process generates a folder at a time; another one waits, then finds it complete.
  std::filesystem::create_directories(request.out);
  const FileLock lock(request.out / ".generate.lock");

  GenerateResult result;
  result.scene_file = request.out / "scene.json";
  result.frames = emitted;
  result.thickness = setup.thickness;
  result.cloth_triangles = 0;
  for (const OutputObject& object : setup.objects) {
    result.triangles += object.faces.size();
    if (object.kind == ObjectKind::deformable) result.cloth_triangles += object.faces.size();
  }
  result.from_cache = complete_in(request.out, setup, key, emitted);

  std::vector<std::unique_ptr<FrameSource>> caches;
  if (!result.from_cache) {
    std::filesystem::remove(request.out / "scene.json");
    std::vector<std::unique_ptr<FrameCacheWriter>> writers;
    for (const OutputObject& object : setup.objects) {
      writers.push_back(std::make_unique<FrameCacheWriter>(request.out / "cache" / (object.name + ".frames"), key,
                                                           object.num_vertices, object.faces));
    }
    for (std::size_t frame = 0; frame < emitted; ++frame) {
      if (frame > 0) setup.simulator->step_fraction(static_cast<int>(parts));
      const double time = time_of(frame);
      std::vector<std::vector<Vec3>> positions;
      for (std::size_t k = 0; k < setup.objects.size(); ++k) {
        positions.push_back(setup.objects[k].positions(*setup.simulator, time));
        for (const Vec3& v : positions.back()) {
          if (!v.allFinite()) {
            throw std::invalid_argument("the simulation of '" + request.name + "' diverged at frame " + std::to_string(frame) +
                                        " (non-finite positions of object '" + setup.objects[k].name + "') with " +
                                        changed_parameters(definition.info, parameters) +
                                        ": a parameter is outside the range where the simulator is stable");
          }
        }
        if (frame < frames_of(setup.objects[k], emitted)) writers[k]->append(positions.back());
      }
      if (request.report) request.report({frame, setup.report(frame, time, positions)});
      if (request.progress) request.progress(frame + 1, emitted);
    }
    for (auto& writer : writers) writer->finish();
  }
  for (const OutputObject& object : setup.objects) {
    caches.push_back(open_frame_cache(request.out / "cache" / (object.name + ".frames")));
  }
  if (result.from_cache && request.report) {
    for (std::size_t frame = 0; frame < emitted; ++frame) {
      std::vector<std::vector<Vec3>> positions;
      for (const auto& cache : caches) positions.push_back(cache->frame(std::min(frame, cache->num_frames() - 1)));
      request.report({frame, setup.report(frame, time_of(frame), positions)});
    }
  }
  if (!result.from_cache) {
    for (std::size_t k = 0; k < setup.objects.size(); ++k) {
      const OutputObject& object = setup.objects[k];
      std::filesystem::remove_all(request.out / object.name);  // no stale frames beyond this count
      if (object.shape) continue;
      for (std::size_t frame = 0; frame < caches[k]->num_frames(); ++frame) {
        write_ply(frame_file(request.out, object.name, frame), {caches[k]->frame(frame), object.faces, ""});
      }
    }
    write_scene_json(request.out, request.name, setup);
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::filesystem::path procedural_cache_root() {
  if (const char* dir = std::getenv("CCDBENCH_CACHE_DIR"); dir && *dir) return dir;
  if (const char* dir = std::getenv("XDG_CACHE_HOME"); dir && *dir) return std::filesystem::path(dir) / "ccdbench";
  if (const char* home = std::getenv("HOME"); home && *home) return std::filesystem::path(home) / ".cache" / "ccdbench";
  return std::filesystem::temp_directory_path() / "ccdbench-cache";
}

void register_procedural_scene_generators() {
  for (const SceneDefinition& definition : definitions()) {
    const std::string name = definition.info.name;
    register_scene_generator(name, [name](const nlohmann::json& block, const std::filesystem::path& file) {
      SceneParameters parameters;
      for (const auto& item : block.items()) {
        if (item.value().is_string()) {
          const auto choice = scene_parameter_choice(name, item.key(), item.value().get<std::string>());
          if (!choice) throw InputError(file, "generator." + item.key(), "must be a number or one of the parameter's choices");
          parameters[item.key()] = *choice;
          continue;
        }
        if (!item.value().is_number()) throw InputError(file, "generator." + item.key(), "must be a number");
        parameters[item.key()] = item.value().get<double>();
      }
      GenerateResult generated;
      try {
        const SceneParameters resolved = resolve_parameters(find_definition(name).info, parameters);
        // FNV-1a of the key names the folder: stable across runs and machines, unlike std::hash.
        std::uint64_t hash = 14695981039346656037ull;
        for (char ch : cache_key(name, resolved)) hash = (hash ^ static_cast<unsigned char>(ch)) * 1099511628211ull;
        std::ostringstream folder;
        folder << name << '-' << std::hex << std::setw(16) << std::setfill('0') << hash;
        generated = generate_procedural_scene({name, resolved, procedural_cache_root() / folder.str(), {}, {}});
      } catch (const std::invalid_argument& error) {
        throw InputError(file, "generator", error.what());
      }
      return load_scene_file(generated.scene_file);
    });
  }
}

}  // namespace ccd::datasets
