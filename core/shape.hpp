#pragma once
/// @file
/// Analytic convex obstacles (docs/DESIGN.md §3, "Model only what a scene requires"): a sphere or an axis-aligned box,
/// given by its size and, per step, by its centre at t = 0 and t = 1 (linear in between). A face and a shape
/// collide in a step when their distance is <= δ at some t in [0, 1]:
/// - sphere: the distance from the face to the centre is <= R + δ (a vertex-face question with thickness R + δ);
/// - box (a solid): the face is within δ of the box's surface, or touches the solid box at t = 0 (a corner inside,
///   or the face cutting through it).
/// A sphere's spin leaves it unchanged, so only its centre moves.

#include "core/vec.hpp"

#include <array>
#include <optional>
#include <string>
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

/// Why a shape is not valid (a radius or half extent not finite and > 0), or nullopt.
std::optional<std::string> find_shape_problem(const Shape& shape);

/// A face's three corners at t = 0 and t = 1 and a shape's centre at t = 0 and t = 1: one face-shape question.
struct FaceShapeRows {
  std::array<Vec3, 3> face_t0;
  std::array<Vec3, 3> face_t1;
  Vec3 centre_t0 = Vec3::Zero();
  Vec3 centre_t1 = Vec3::Zero();
};

/// The box's eight corners around `centre`, corner i at centre + (±h.x, ±h.y, ±h.z) with bit k of i choosing the
/// sign of axis k (set: +), each coordinate one addition or subtraction: rounded for Vec3 (the strategies), exact
/// for rational points (the reference).
template <class Point>
std::array<Point, 8> box_corners(const Point& centre, const Point& half_extents) {
  std::array<Point, 8> corners;
  for (int i = 0; i < 8; ++i) {
    for (int k = 0; k < 3; ++k) {
      corners[i][k] = centre[k];
      if ((i >> k) & 1) {
        corners[i][k] += half_extents[k];
      } else {
        corners[i][k] -= half_extents[k];
      }
    }
  }
  return corners;
}

/// The box's twelve surface triangles (two per side, outward counter-clockwise) and its twelve edges, as corner
/// indices of box_corners.
extern const std::array<std::array<int, 3>, 12> kBoxTriangles;
extern const std::array<std::array<int, 2>, 12> kBoxEdges;

/// The elementary pairs whose decisions at δ decide whether a face comes within δ of a box's surface during the
/// step: the face's corners against each surface triangle, the box's corners against the face, and the face's
/// edges against the box's twelve edges. Between a triangle and a convex polygon that do not touch, the distance is
/// reached by a corner against the other or by two boundary edges, so the sides' diagonals add nothing. Calls
/// visit(vertex_face, rows) with rows in the query files' order (step.hpp) and stops when it returns true. Both the
/// reference (exact corners) and the strategies (rounded corners) decide this same list.
template <class Point, class Visit>
void for_each_box_surface_pair(const std::array<Point, 3>& face_t0, const std::array<Point, 3>& face_t1, const std::array<Point, 8>& corners_t0,
                               const std::array<Point, 8>& corners_t1, Visit visit) {
  const auto& f0 = face_t0;
  const auto& f1 = face_t1;
  const auto& c0 = corners_t0;
  const auto& c1 = corners_t1;
  for (int i = 0; i < 3; ++i) {
    for (const auto& t : kBoxTriangles) {
      if (visit(true, std::array<Point, 8>{f0[i], c0[t[0]], c0[t[1]], c0[t[2]], f1[i], c1[t[0]], c1[t[1]], c1[t[2]]})) return;
    }
  }
  for (int j = 0; j < 8; ++j) {
    if (visit(true, std::array<Point, 8>{c0[j], f0[0], f0[1], f0[2], c1[j], f1[0], f1[1], f1[2]})) return;
  }
  for (int i = 0; i < 3; ++i) {
    const int k = (i + 1) % 3;
    for (const auto& e : kBoxEdges) {
      if (visit(false, std::array<Point, 8>{f0[i], f0[k], c0[e[0]], c0[e[1]], f1[i], f1[k], c1[e[0]], c1[e[1]]})) return;
    }
  }
}

}  // namespace ccd
