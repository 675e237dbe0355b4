#pragma once
/// @file
/// Geometric vocabulary: the scalar, 3-vectors, boxes and the id types every folder shares.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <span>

namespace ccd {

/// The scalar of all positions. Double by default; the float variants of a narrow phase convert on purpose
/// at their own entry instead of templating the project on the scalar (STYLE.md "Shape").
using Scalar = double;
using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
/// Axis-aligned box; an empty box has min > max (Eigen's convention).
using Box3 = Eigen::AlignedBox<Scalar, 3>;

using VertexId = std::uint32_t;
using EdgeId = std::uint32_t;
using FaceId = std::uint32_t;
using ObjectId = std::uint32_t;

/// Smallest box that holds every point of `points` (empty box for no points).
Box3 bounding_box(std::span<const Vec3> points);

}  // namespace ccd
