#pragma once
/// @file
/// Triangle meshes of the shapes procedural scenes are made of: cloth grids and obstacles.

#include "core/topology.hpp"
#include "core/vec.hpp"

#include <vector>

namespace ccd::datasets {

struct ShapeMesh {
  std::vector<Vec3> positions;
  std::vector<Face> faces;
};

/// An n x n vertex grid of side `size` centred at the origin in the z = 0 plane, vertex (i, j) at index i·n + j
/// with x growing with j and y with i; 2(n-1)² triangles, diagonals alternating so the cloth has no bias.
ShapeMesh cloth_grid(std::size_t n, double size);

/// A sphere of `radius` at the origin: `rings` latitude bands, `segments` longitudes, outward-facing.
ShapeMesh uv_sphere(double radius, std::size_t rings, std::size_t segments);

/// A closed box between `lower` and `upper` (12 triangles).
ShapeMesh box(const Vec3& lower, const Vec3& upper);

/// The open side surface of a frustum around the z axis: radius r_bottom at z_bottom to r_top at z_top.
ShapeMesh frustum(double r_bottom, double z_bottom, double r_top, double z_top, std::size_t segments);

}  // namespace ccd::datasets
