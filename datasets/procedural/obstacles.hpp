#pragma once
/// @file
/// The simulator's analytic obstacles of the built-in scenes (datasets/cloth_simulator.hpp): a particle that enters
/// one is projected out through the nearest side, with friction. Their meshes (or shapes) are what strategies see.

#include "core/vec.hpp"
#include "datasets/cloth_simulator.hpp"

#include <functional>
#include <memory>

namespace ccd::datasets::procedural {

/// A sphere at the origin spinning about z with angular speed omega(time).
std::shared_ptr<const Obstacle> sphere_obstacle(double radius, double friction, std::function<double(double)> omega);
/// The half space above z = height.
std::shared_ptr<const Obstacle> plane_obstacle(double height, double friction);
/// A solid axis-aligned box.
std::shared_ptr<const Obstacle> box_obstacle(const Vec3& lower, const Vec3& upper, double friction);
/// The inside of a funnel around z: between z_bottom and z_top a particle stays within the radius there.
std::shared_ptr<const Obstacle> funnel_obstacle(double r_bottom, double z_bottom, double r_top, double z_top, double friction);

}  // namespace ccd::datasets::procedural
