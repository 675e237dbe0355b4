#pragma once
/// @file
/// The reference's face-shape decision (core/shape.hpp says what collides): exact, with the elementary decisions of
/// elementary_pair.hpp.
///
/// - Sphere: one vertex-face pair, the centre against the face, at thickness R + δ formed exactly in rationals.
/// - Box: the face against the box's surface, corners c ± h formed exactly in rationals, by the elementary pairs of
///   for_each_box_surface_pair (core/shape.hpp). Then the solid: whether the face at t = 0 meets the closed box,
///   by the separating-axis test of a triangle and a box (13 axes) in rationals. A face that starts outside
///   touches the surface before it can be inside.

#include "core/shape.hpp"
#include "reference/elementary_pair.hpp"

namespace ccd::reference {

/// Decides whether the face and the shape come within δ at some t in [0, 1]. The TOI, with request.want_toi, is
/// the earliest over the elementary decisions (0 when the face meets the solid box at t = 0).
/// @throws std::invalid_argument for a non-finite coordinate, radius or half extent, or a negative δ.
Decision decide_face_shape(const Shape& shape, const FaceShapeRows& rows, double thickness, const DecisionRequest& request = {});

/// Whether the triangle (exact rational corners) meets the closed axis-aligned box of that centre and those half
/// extents: no one of the 13 axes of the separating-axis test separates them (strict inequalities).
bool triangle_meets_box(const std::array<RationalPoint, 3>& triangle, const RationalPoint& centre, const RationalPoint& half_extents);

}  // namespace ccd::reference
