#include "datasets/cloth_simulator.hpp"

#include "datasets/shapes.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>

namespace ccd::datasets {
namespace {

/// The six constraint families of a grid cloth: (row step, column step).
constexpr std::array<std::array<int, 2>, 6> kFamilies = {{{0, 1}, {1, 0}, {1, 1}, {1, -1}, {0, 2}, {2, 0}}};

}  // namespace

ClothSimulator::ClothSimulator(SimulatorSettings settings) : settings_(settings) { constraint_groups_.resize(2 * kFamilies.size()); }

std::size_t ClothSimulator::add_cloth(std::size_t n, const std::vector<Vec3>& positions) {
  const std::size_t first = x_.size();
  const auto cloth = static_cast<std::uint32_t>(cloths_.size());
  cloths_.push_back({first, n});
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      x_.push_back(positions[i * n + j]);
      v_.emplace_back(0, 0, 0);
      inverse_mass_.push_back(1.0);
      tags_.push_back({cloth, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)});
    }
  }
  p_ = x_;
  auto index = [&](std::size_t i, std::size_t j) { return static_cast<std::uint32_t>(first + i * n + j); };
  for (std::size_t f = 0; f < kFamilies.size(); ++f) {
    const int di = kFamilies[f][0], dj = kFamilies[f][1];
    const double stiffness = f < 2 ? settings_.stretch_stiffness : f < 4 ? settings_.shear_stiffness : settings_.bend_stiffness;
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t j = 0; j < n; ++j) {
        const long i2 = static_cast<long>(i) + di, j2 = static_cast<long>(j) + dj;
        if (i2 < 0 || j2 < 0 || i2 >= static_cast<long>(n) || j2 >= static_cast<long>(n)) continue;
        // A constraint and its neighbour along the family's step differ by one in (index / step) along the
        // stepping axis, so that parity is a 2-colouring with no shared particle inside a colour.
        const std::size_t along = di != 0 ? i / static_cast<std::size_t>(std::abs(di)) : j / static_cast<std::size_t>(std::abs(dj));
        const std::uint32_t a = index(i, j), b = index(static_cast<std::size_t>(i2), static_cast<std::size_t>(j2));
        constraint_groups_[2 * f + along % 2].push_back({a, b, (x_[a] - x_[b]).norm(), stiffness});
      }
    }
  }
  const ShapeMesh grid = cloth_grid(n, 1.0);
  for (const Face& face : grid.faces) {
    triangles_.push_back(
        {static_cast<std::uint32_t>(first + face[0]), static_cast<std::uint32_t>(first + face[1]), static_cast<std::uint32_t>(first + face[2])});
  }
  std::vector<std::vector<std::uint32_t>> incident(x_.size());
  for (std::uint32_t t = 0; t < triangles_.size(); ++t) {
    for (std::uint32_t v : triangles_[t]) incident[v].push_back(t);
  }
  particle_triangle_begin_.assign(1, 0);
  particle_triangles_.clear();
  for (const auto& list : incident) {
    particle_triangles_.insert(particle_triangles_.end(), list.begin(), list.end());
    particle_triangle_begin_.push_back(static_cast<std::uint32_t>(particle_triangles_.size()));
  }
  return first;
}

void ClothSimulator::set_kinematic(std::size_t index, std::function<Vec3(double)> path) {
  inverse_mass_[index] = 0.0;
  x_[index] = p_[index] = path(time_);
  kinematic_.emplace_back(index, std::move(path));
}

void ClothSimulator::add_obstacle(std::shared_ptr<const Obstacle> obstacle) { obstacles_.push_back(std::move(obstacle)); }

void ClothSimulator::set_wind(std::function<Vec3(double)> wind, double normal_drag, double tangential_drag) {
  wind_ = std::move(wind);
  normal_drag_ = normal_drag;
  tangential_drag_ = tangential_drag;
}

void ClothSimulator::step_frame() { step_fraction(1); }

void ClothSimulator::step_fraction(int parts) {
  const int per_part = (settings_.substeps + parts - 1) / parts;
  const double dt = settings_.frame_seconds / (per_part * parts);
  for (int s = 0; s < per_part; ++s) substep(dt);
}

void ClothSimulator::apply_wind(double dt) {
  const Vec3 wind = wind_(time_);
  // Gather per particle: the area-weighted mean of its triangles' drag accelerations. The gather reads the
  // velocities of neighbours, so accelerations go to their own buffer and are applied after all are computed.
  std::vector<Vec3> acceleration(x_.size(), Vec3(0, 0, 0));
  tbb::parallel_for(std::size_t{0}, x_.size(), [&](std::size_t v) {
    if (inverse_mass_[v] == 0.0) return;
    Vec3 weighted(0, 0, 0);
    double total_area = 0.0;
    for (std::uint32_t k = particle_triangle_begin_[v]; k < particle_triangle_begin_[v + 1]; ++k) {
      const auto& t = triangles_[particle_triangles_[k]];
      const Vec3 area_normal = 0.5 * (x_[t[1]] - x_[t[0]]).cross(x_[t[2]] - x_[t[0]]);
      const double area = area_normal.norm();
      if (area == 0.0) continue;
      const Vec3 normal = area_normal / area;
      const Vec3 relative = wind - (v_[t[0]] + v_[t[1]] + v_[t[2]]) / 3.0;
      const double speed = relative.norm();
      const double across = relative.dot(normal);
      weighted += area * speed * (normal_drag_ * across * normal + tangential_drag_ * (relative - across * normal));
      total_area += area;
    }
    if (total_area > 0.0) acceleration[v] = weighted / total_area;
  });
  tbb::parallel_for(std::size_t{0}, x_.size(), [&](std::size_t v) { v_[v] += dt * acceleration[v]; });
}

void ClothSimulator::substep(double dt) {
  if (wind_) apply_wind(dt);
  tbb::parallel_for(std::size_t{0}, x_.size(), [&](std::size_t v) {
    if (inverse_mass_[v] == 0.0) return;
    v_[v] = settings_.damping * (v_[v] + dt * settings_.gravity);
    p_[v] = x_[v] + dt * v_[v];
  });
  for (const auto& [index, path] : kinematic_) p_[index] = path(time_ + dt);

  for (int iteration = 0; iteration < settings_.iterations; ++iteration) {
    for (const auto& group : constraint_groups_) {
      tbb::parallel_for(std::size_t{0}, group.size(), [&](std::size_t c) {
        const DistanceConstraint& constraint = group[c];
        const double wa = inverse_mass_[constraint.a], wb = inverse_mass_[constraint.b];
        if (wa + wb == 0.0) return;
        const Vec3 d = p_[constraint.b] - p_[constraint.a];
        const double length = d.norm();
        if (length == 0.0) return;
        const Vec3 correction = constraint.stiffness * (length - constraint.rest) / ((wa + wb) * length) * d;
        p_[constraint.a] += wa * correction;
        p_[constraint.b] -= wb * correction;
      });
    }
  }
  if (settings_.repulsion_radius > 0.0) self_repulsion();
  tbb::parallel_for(std::size_t{0}, x_.size(), [&](std::size_t v) {
    if (inverse_mass_[v] == 0.0) return;
    for (const auto& obstacle : obstacles_) obstacle->project(p_[v], x_[v], time_, dt);
  });
  tbb::parallel_for(std::size_t{0}, x_.size(), [&](std::size_t v) {
    Vec3 velocity = (p_[v] - x_[v]) / dt;
    const double speed = velocity.norm();
    if (speed > settings_.max_speed) velocity *= settings_.max_speed / speed;
    if (inverse_mass_[v] != 0.0) v_[v] = velocity;
    x_[v] = inverse_mass_[v] == 0.0 ? p_[v] : x_[v] + dt * velocity;
  });
  time_ += dt;
}

void ClothSimulator::self_repulsion() {
  const double radius = settings_.repulsion_radius;
  // A diverging simulation (caught after the frame, with the parameter named) may hold huge or non-finite
  // positions here: their cells are clamped into range (NaN to 0) so that converting them is defined.
  auto cell_of = [radius](const Vec3& p) {
    auto cell = [radius](double x) {
      const double c = std::floor(x / radius);
      return static_cast<long long>(c >= -0x1p40 && c <= 0x1p40 ? c : c > 0 ? 0x1p40 : c < 0 ? -0x1p40 : 0.0);
    };
    return std::array<long long, 3>{cell(p.x()), cell(p.y()), cell(p.z())};
  };
  auto key_of = [](const std::array<long long, 3>& c) {
    // 21 bits per axis: a cloth of a few metres at millimetre radii stays far inside that range.
    const auto bits = [](long long v) { return static_cast<std::uint64_t>(v + (1 << 20)) & 0x1FFFFF; };
    return (bits(c[0]) << 42) | (bits(c[1]) << 21) | bits(c[2]);
  };
  std::vector<std::pair<std::uint64_t, std::uint32_t>> sorted(p_.size());
  tbb::parallel_for(std::size_t{0}, p_.size(), [&](std::size_t v) { sorted[v] = {key_of(cell_of(p_[v])), static_cast<std::uint32_t>(v)}; });
  tbb::parallel_sort(sorted.begin(), sorted.end());
  std::vector<Vec3> correction(p_.size(), Vec3(0, 0, 0));
  tbb::parallel_for(std::size_t{0}, p_.size(), [&](std::size_t v) {
    if (inverse_mass_[v] == 0.0) return;
    const auto cell = cell_of(p_[v]);
    const ParticleTag& tag = tags_[v];
    Vec3 push(0, 0, 0);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const std::uint64_t key = key_of({cell[0] + dx, cell[1] + dy, cell[2] + dz});
          auto it = std::lower_bound(sorted.begin(), sorted.end(), std::pair<std::uint64_t, std::uint32_t>(key, 0));
          for (; it != sorted.end() && it->first == key; ++it) {
            const std::uint32_t u = it->second;
            const ParticleTag& other = tags_[u];
            // Grid neighbours within two rings are held by the constraints; repelling them would fight those.
            if (u == v || (other.cloth == tag.cloth && std::abs(static_cast<long>(other.i) - static_cast<long>(tag.i)) <= 2 &&
                           std::abs(static_cast<long>(other.j) - static_cast<long>(tag.j)) <= 2)) {
              continue;
            }
            const Vec3 d = p_[v] - p_[u];
            const double distance = d.norm();
            if (distance >= radius || distance == 0.0) continue;
            push += 0.5 * (radius - distance) / distance * d;
          }
        }
      }
    }
    correction[v] = push;
  });
  tbb::parallel_for(std::size_t{0}, p_.size(), [&](std::size_t v) { p_[v] += correction[v]; });
}

}  // namespace ccd::datasets
