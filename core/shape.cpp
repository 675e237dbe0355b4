#include "core/shape.hpp"

#include <cmath>

namespace ccd {

std::string_view to_string(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::sphere: return "sphere";
    case ShapeKind::box: return "box";
  }
  return "?";
}

std::optional<std::string> find_shape_problem(const Shape& shape) {
  auto positive = [](double x) { return std::isfinite(x) && x > 0.0; };
  if (shape.kind == ShapeKind::sphere) {
    if (!positive(shape.radius)) return "a sphere's radius must be finite and > 0";
  } else if (!positive(shape.half_extents.x()) || !positive(shape.half_extents.y()) || !positive(shape.half_extents.z())) {
    return "a box's half extents must be finite and > 0";
  }
  return std::nullopt;
}

// Sides -x, +x, -y, +y, -z, +z, each split along one diagonal; the cross product of each triangle's first two
// edges points out of the box.
const std::array<std::array<int, 3>, 12> kBoxTriangles{
    {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}, {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3}, {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}}};

const std::array<std::array<int, 2>, 12> kBoxEdges{{{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3}, {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}}};

}  // namespace ccd
