#pragma once
/// @file
/// Geometric vocabulary: the scalar, 3-vectors, boxes and the id types every folder shares.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <span>

namespace ccd {

/// The scalar of all positions. Double by default; the float variants of a narrow phase convert on purpose
/// at their own entry instead of templating the project on the scalar (docs/STYLE.md "Shape").
using Scalar = double;
using Vec3 = Eigen::Matrix<Scalar, 3, 1>;
/// Axis-aligned box; an empty box has min > max (Eigen's convention).
using Box3 = Eigen::AlignedBox<Scalar, 3>;

using VertexId = std::uint32_t;
using EdgeId = std::uint32_t;
using FaceId = std::uint32_t;
using ObjectId = std::uint32_t;

/// Whether two boxes share a point (touching counts): Eigen's AlignedBox::intersects, written out so that it is inlined
/// where it runs hundreds of millions of times a step (BVH traversals, apccd's front end, the elementary box cull);
/// GCC kept Eigen's out of line there (perf: 7% of apccd's CPU step). The same answer for every input, NaN included
/// (every comparison with NaN is false).
inline bool boxes_overlap(const Box3& a, const Box3& b) {
  const Scalar* a_min = a.min().data();
  const Scalar* a_max = a.max().data();
  const Scalar* b_min = b.min().data();
  const Scalar* b_max = b.max().data();
  return (a_min[0] <= b_max[0]) & (a_min[1] <= b_max[1]) & (a_min[2] <= b_max[2]) & (b_min[0] <= a_max[0]) & (b_min[1] <= a_max[1]) &
         (b_min[2] <= a_max[2]);
}

/// Smallest box that holds every point of `points` (empty box for no points).
Box3 bounding_box(std::span<const Vec3> points);

}  // namespace ccd
