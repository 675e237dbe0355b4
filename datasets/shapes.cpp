#include "datasets/shapes.hpp"

#include <cmath>
#include <numbers>

namespace ccd::datasets {

ShapeMesh cloth_grid(std::size_t n, double size) {
  ShapeMesh mesh;
  const double spacing = size / static_cast<double>(n - 1);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      mesh.positions.emplace_back(-size / 2 + spacing * static_cast<double>(j), -size / 2 + spacing * static_cast<double>(i), 0.0);
    }
  }
  for (std::size_t i = 0; i + 1 < n; ++i) {
    for (std::size_t j = 0; j + 1 < n; ++j) {
      const auto a = static_cast<VertexId>(i * n + j), b = a + 1, c = static_cast<VertexId>(a + n), d = c + 1;
      if ((i + j) % 2 == 0) {
        mesh.faces.push_back({a, b, d});
        mesh.faces.push_back({a, d, c});
      } else {
        mesh.faces.push_back({a, b, c});
        mesh.faces.push_back({b, d, c});
      }
    }
  }
  return mesh;
}

ShapeMesh uv_sphere(double radius, std::size_t rings, std::size_t segments) {
  ShapeMesh mesh;
  mesh.positions.emplace_back(0, 0, -radius);
  for (std::size_t r = 1; r < rings; ++r) {
    const double polar = std::numbers::pi * static_cast<double>(r) / static_cast<double>(rings);
    for (std::size_t s = 0; s < segments; ++s) {
      const double azimuth = 2 * std::numbers::pi * static_cast<double>(s) / static_cast<double>(segments);
      mesh.positions.emplace_back(radius * std::sin(polar) * std::cos(azimuth), radius * std::sin(polar) * std::sin(azimuth),
                                  -radius * std::cos(polar));
    }
  }
  mesh.positions.emplace_back(0, 0, radius);
  const auto top = static_cast<VertexId>(mesh.positions.size() - 1);
  auto ring_vertex = [&](std::size_t r, std::size_t s) { return static_cast<VertexId>(1 + (r - 1) * segments + s % segments); };
  for (std::size_t s = 0; s < segments; ++s) {
    mesh.faces.push_back({0, ring_vertex(1, s + 1), ring_vertex(1, s)});
    mesh.faces.push_back({top, ring_vertex(rings - 1, s), ring_vertex(rings - 1, s + 1)});
  }
  for (std::size_t r = 1; r + 1 < rings; ++r) {
    for (std::size_t s = 0; s < segments; ++s) {
      mesh.faces.push_back({ring_vertex(r, s), ring_vertex(r, s + 1), ring_vertex(r + 1, s + 1)});
      mesh.faces.push_back({ring_vertex(r, s), ring_vertex(r + 1, s + 1), ring_vertex(r + 1, s)});
    }
  }
  return mesh;
}

ShapeMesh box(const Vec3& lower, const Vec3& upper) {
  ShapeMesh mesh;
  for (int k = 0; k < 8; ++k) {
    mesh.positions.emplace_back(k & 1 ? upper.x() : lower.x(), k & 2 ? upper.y() : lower.y(), k & 4 ? upper.z() : lower.z());
  }
  // Two outward-facing triangles per side.
  mesh.faces = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return mesh;
}

ShapeMesh frustum(double r_bottom, double z_bottom, double r_top, double z_top, std::size_t segments) {
  ShapeMesh mesh;
  for (std::size_t s = 0; s < segments; ++s) {
    const double azimuth = 2 * std::numbers::pi * static_cast<double>(s) / static_cast<double>(segments);
    mesh.positions.emplace_back(r_bottom * std::cos(azimuth), r_bottom * std::sin(azimuth), z_bottom);
    mesh.positions.emplace_back(r_top * std::cos(azimuth), r_top * std::sin(azimuth), z_top);
  }
  for (std::size_t s = 0; s < segments; ++s) {
    const auto b0 = static_cast<VertexId>(2 * s), t0 = b0 + 1;
    const auto b1 = static_cast<VertexId>(2 * ((s + 1) % segments)), t1 = b1 + 1;
    mesh.faces.push_back({b0, b1, t1});
    mesh.faces.push_back({b0, t1, t0});
  }
  return mesh;
}

}  // namespace ccd::datasets
