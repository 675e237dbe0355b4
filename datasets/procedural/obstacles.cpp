#include "datasets/procedural/obstacles.hpp"

#include <cmath>
#include <limits>

namespace ccd::datasets::procedural {
namespace {

/// Removes the motion of a projected particle relative to the surface, tangentially, by `friction` (1 sticks).
void apply_friction(Vec3& q, const Vec3& previous, const Vec3& normal, const Vec3& surface_velocity, double dt, double friction) {
  const Vec3 relative = (q - previous) - surface_velocity * dt;
  q -= friction * (relative - relative.dot(normal) * normal);
}

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

}  // namespace

std::shared_ptr<const Obstacle> sphere_obstacle(double radius, double friction, std::function<double(double)> omega) {
  return std::make_shared<SphereObstacle>(radius, friction, std::move(omega));
}

std::shared_ptr<const Obstacle> plane_obstacle(double height, double friction) { return std::make_shared<PlaneObstacle>(height, friction); }

std::shared_ptr<const Obstacle> box_obstacle(const Vec3& lower, const Vec3& upper, double friction) {
  return std::make_shared<BoxObstacle>(lower, upper, friction);
}

std::shared_ptr<const Obstacle> funnel_obstacle(double r_bottom, double z_bottom, double r_top, double z_top, double friction) {
  return std::make_shared<FunnelObstacle>(r_bottom, z_bottom, r_top, z_top, friction);
}

}  // namespace ccd::datasets::procedural
