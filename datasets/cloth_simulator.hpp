#pragma once
/// @file
/// A small, deterministic position-based-dynamics cloth simulator: the data generator behind the procedural
/// scenes (it is not what ccdbench measures, so it stays small and readable).
///
/// Per substep: explicit prediction (gravity, wind drag, damping), then `iterations` sweeps of distance
/// constraints (stretch along grid edges, shear along cell diagonals, bending across two cells), then one pass of
/// vertex-vertex self-repulsion, then obstacle projection with friction. Determinism for any thread count comes
/// from structure, not from running serially: constraints are grouped by family and colour so that no two
/// constraints of a group share a particle (a group runs in parallel; groups run in a fixed order), and repulsion
/// and wind are per-particle gathers that read shared state and write only their own particle.

#include "core/vec.hpp"

#include <functional>
#include <memory>
#include <vector>

namespace ccd::datasets {

/// Something cloth rests on. Implementations move a predicted particle position out of themselves and apply
/// friction against their own surface velocity.
class Obstacle {
 public:
  virtual ~Obstacle() = default;
  /// @param predicted the particle's predicted position at time + dt; moved out of the obstacle when inside
  /// @param previous  its position at time
  virtual void project(Vec3& predicted, const Vec3& previous, double time, double dt) const = 0;
};

struct SimulatorSettings {
  double frame_seconds = 1.0 / 30.0;
  int substeps = 4;
  int iterations = 6;
  Vec3 gravity{0.0, 0.0, -9.81};
  /// Velocity kept per substep (air damping).
  double damping = 0.998;
  double stretch_stiffness = 1.0;
  double shear_stiffness = 0.6;
  double bend_stiffness = 0.15;
  /// Vertices of different grid neighbourhoods are kept this far apart (0: no self-repulsion).
  double repulsion_radius = 0.0;
  /// Speed clamp (m/s): a safety net that keeps a rare bad configuration from exploding.
  double max_speed = 20.0;
};

class ClothSimulator {
 public:
  explicit ClothSimulator(SimulatorSettings settings);

  /// Adds an n x n grid cloth (vertex (i, j) at positions[i·n + j]); rest lengths come from these positions.
  /// @return the index of its first particle.
  std::size_t add_cloth(std::size_t n, const std::vector<Vec3>& positions);
  /// Particle `index` follows `path(time)` exactly and is never moved by constraints or contacts.
  void set_kinematic(std::size_t index, std::function<Vec3(double)> path);
  void add_obstacle(std::shared_ptr<const Obstacle> obstacle);
  /// A wind velocity field w(time). With r = w - v the air's velocity relative to a triangle and n its normal,
  /// the triangle feels quadratic drag per unit mass, normal_drag·(r·n)|r| n + tangential_drag·|r| r_tangential;
  /// a particle takes the area-weighted mean over its triangles, so the effect does not depend on resolution.
  void set_wind(std::function<Vec3(double)> wind, double normal_drag, double tangential_drag);

  /// Advances by one frame (settings.frame_seconds).
  void step_frame();
  /// Advances 1/parts of a frame: ceil(substeps / parts) substeps of frame_seconds / (that · parts), so that
  /// `parts` calls make one frame. parts = 1 is step_frame(); parts dividing `substeps` (1, 2, 4 with the default
  /// 4) keep its substeps, and so its motion, bit for bit; others take the next multiple of parts.
  void step_fraction(int parts);

  const std::vector<Vec3>& positions() const { return x_; }
  double time() const { return time_; }

 private:
  struct DistanceConstraint {
    std::uint32_t a, b;
    double rest;
    double stiffness;
  };
  struct ParticleTag {
    std::uint32_t cloth, i, j;
  };
  struct Cloth {
    std::size_t first, n;
  };

  void substep(double dt);
  void apply_wind(double dt);
  void self_repulsion();

  SimulatorSettings settings_;
  double time_ = 0.0;
  std::vector<Vec3> x_, v_, p_;
  std::vector<double> inverse_mass_;
  std::vector<ParticleTag> tags_;
  std::vector<Cloth> cloths_;
  std::vector<std::array<std::uint32_t, 3>> triangles_;
  /// For each particle, the triangles it belongs to (compressed), for the wind gather.
  std::vector<std::uint32_t> particle_triangle_begin_, particle_triangles_;
  /// Independent groups in their fixed order (family, colour).
  std::vector<std::vector<DistanceConstraint>> constraint_groups_;
  std::vector<std::pair<std::size_t, std::function<Vec3(double)>>> kinematic_;
  std::vector<std::shared_ptr<const Obstacle>> obstacles_;
  std::function<Vec3(double)> wind_;
  double normal_drag_ = 0.0;
  double tangential_drag_ = 0.0;
};

}  // namespace ccd::datasets
