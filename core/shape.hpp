#pragma once
/// @file
/// Analytic convex obstacles (DESIGN.md §3, "Model only what a scene requires"): a sphere or an axis-aligned box,
/// given by its size and, per step, by its centre at t = 0 and t = 1 (linear in between). A face and a shape
/// collide in a step when their distance is <= δ at some t in [0, 1]:
/// - sphere: the distance from the face to the centre is <= R + δ (a vertex-face question with thickness R + δ);
/// - box (a solid): the face is within δ of the box's surface, or touches the solid box at t = 0 (a corner inside,
///   or the face cutting through it).
/// A sphere's spin leaves it unchanged, so only its centre moves.

#include "core/vec.hpp"

#include <array>
#include <string_view>

namespace ccd {

enum class ShapeKind { sphere, box };

std::string_view to_string(ShapeKind kind);

struct Shape {
  ShapeKind kind = ShapeKind::sphere;
  /// Sphere only: R > 0, finite.
  double radius = 0.0;
  /// Box only: every component > 0, finite.
  Vec3 half_extents = Vec3::Zero();
};

/// A face's three corners at t = 0 and t = 1 and a shape's centre at t = 0 and t = 1: one face-shape question.
struct FaceShapeRows {
  std::array<Vec3, 3> face_t0;
  std::array<Vec3, 3> face_t1;
  Vec3 centre_t0 = Vec3::Zero();
  Vec3 centre_t1 = Vec3::Zero();
};

/// The box's eight corners around `centre`, corner i at centre + (±h.x, ±h.y, ±h.z) with bit k of i choosing the
/// sign of axis k (set: +). Computed in doubles (rounded); the reference forms them exactly.
std::array<Vec3, 8> box_corners(const Vec3& centre, const Vec3& half_extents);

/// The box's twelve surface triangles (two per side, outward counter-clockwise) and its twelve edges, as corner
/// indices of box_corners.
extern const std::array<std::array<int, 3>, 12> kBoxTriangles;
extern const std::array<std::array<int, 2>, 12> kBoxEdges;

}  // namespace ccd
