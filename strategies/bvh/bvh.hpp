#pragma once
/// @file
/// A bounding volume hierarchy over an object's triangles, for swept-volume culling.
///
/// The bounding volume is the axis-aligned box: cloth deforms every step, so volumes are refitted, never rebuilt,
/// and an AABB refits in one bottom-up pass of min/max; it stays valid under any deformation, where an OBB would
/// need its axes refitted and a k-DOP pays k/3 times the refit and overlap cost for tighter volumes that a cloth
/// mesh's small, nearly flat triangles do not need.

#include "core/topology.hpp"
#include "core/vec.hpp"

#include <limits>
#include <span>
#include <vector>

namespace ccd::bvh {

/// A face's box over the step, x0 ∪ x1, widened by `inflation` on every side (and a rounding margin).
Box3 swept_face_box(const Face& face, std::span<const Vec3> x0, std::span<const Vec3> x1, double inflation);

/// Relative room for the rounding of widened boxes: a corner c ± w (w the widening) is computed in one or two
/// roundings of values of magnitude |c| + w, at most 2u = 2^-52 of it; 2^-50 of it covers them at every scale, and
/// the smallest subnormal covers corners that underflow. So two primitives within 2w always get overlapping boxes.
inline constexpr double kBoxRoundingMargin = 0x1p-50;

/// Widens `box` by widening[k] on both sides along axis k, with the rounding room above.
inline Box3 widened(const Box3& box, const Vec3& widening) {
  const auto room = [&](const Vec3& corner) {
    return Vec3((corner.cwiseAbs().array() + widening.array()) * kBoxRoundingMargin + widening.array() + std::numeric_limits<double>::denorm_min());
  };
  return Box3(box.min() - room(box.min()), box.max() + room(box.max()));
}

/// Widens `box` by `widening` on every side, with the rounding room above.
inline Box3 widened(const Box3& box, double widening) { return widened(box, Vec3::Constant(widening)); }

class TriangleBvh {
 public:
  struct Node {
    Box3 box;
    /// Children (internal node), or -1 and the leaf's global face id.
    std::int32_t left = -1;
    std::int32_t right = -1;
    FaceId face = 0;
    /// The largest face id under the node (in the node's tail padding): a self query from face a skips subtrees
    /// with no face above a, whose pairs the smaller face's own query finds.
    FaceId max_face = 0;

    bool is_leaf() const { return left < 0; }
  };
  static_assert(sizeof(Node) == 64, "a node is one cache line: max_face lives in its tail padding");

  /// Builds over the global faces [first_face, first_face + face_count) of `topology` from one frame's positions:
  /// top-down, splitting at the median centroid along the widest axis, down to one face per leaf (so a leaf's box
  /// is its face's box and leaf overlaps are face overlaps).
  void build(const MeshTopology& topology, FaceId first_face, std::size_t face_count, std::span<const Vec3> x);

  /// Leaf boxes become the faces' swept boxes over x0 -> x1 widened by `inflation`, internal nodes their union.
  void refit(const MeshTopology& topology, std::span<const Vec3> x0, std::span<const Vec3> x1, double inflation);
  /// The same with a per-face widening (`inflation[f - first_face]`), for strategies that inflate by local motion.
  void refit(const MeshTopology& topology, std::span<const Vec3> x0, std::span<const Vec3> x1, std::span<const double> inflation);

  /// Grows the leaf box of global face f to also hold `box`, and its ancestors with it: the hierarchy stays valid
  /// for a face that moved beyond the box it was fitted with.
  void enlarge_leaf(FaceId f, const Box3& box);

  const std::vector<Node>& nodes() const { return nodes_; }
  FaceId first_face() const { return first_face_; }
  std::size_t face_count() const { return leaf_of_face_.size(); }
  /// Levels below the root of the deepest leaf (0 for a single face).
  int depth() const { return depth_; }
  bool empty() const { return nodes_.empty(); }
  /// The leaf node of global face f (f in this tree's range).
  std::int32_t leaf_of(FaceId f) const { return leaf_of_face_[f - first_face_]; }
  /// Bytes held by the hierarchy (for memory reports).
  std::size_t bytes() const { return nodes_.size() * sizeof(Node) + leaf_of_face_.size() * sizeof(std::int32_t); }

 private:
  template <class Inflation>
  void refit_with(const MeshTopology& topology, std::span<const Vec3> x0, std::span<const Vec3> x1, Inflation inflation);

  std::vector<Node> nodes_;
  std::vector<std::int32_t> leaf_of_face_;
  std::vector<std::int32_t> parent_;
  /// Internal nodes in an order where children come before parents (bottom-up refit order).
  std::vector<std::int32_t> bottom_up_;
  FaceId first_face_ = 0;
  int depth_ = 0;
};

/// A candidate: two distinct global face ids, a < b.
using TrianglePair = std::pair<FaceId, FaceId>;

/// Every pair of distinct faces of `tree` whose boxes overlap, each once, sorted. Parallel; the result does not
/// depend on the thread count. One query per face (its leaf box from the root down, keeping the larger ids), in
/// chunks of consecutive face ids whose sorted lists are concatenated in order: no sort and no merge of the whole
/// list (benchmarks/bvh_benchmark.cpp chose it over self_overlaps_tree_pairs on the public steps, reports/cpu-step).
std::vector<TrianglePair> self_overlaps(const TriangleBvh& tree);
/// The same pairs by the simultaneous descent of the tree against itself (node pairs, then a parallel sort of the
/// whole list): the design self_overlaps replaced, kept for the benchmark that compares them.
std::vector<TrianglePair> self_overlaps_tree_pairs(const TriangleBvh& tree);
/// Every pair (face of a, face of b) whose boxes overlap, as (smaller id, larger id), sorted. With `b_offset`,
/// b's boxes are first swept by that box of translations (b's frame moved relative to a's).
std::vector<TrianglePair> pair_overlaps(const TriangleBvh& a, const TriangleBvh& b, const Box3& b_offset = Box3(Vec3::Zero(), Vec3::Zero()));

/// Pairs (f, g), f in `subset` with box `subset_boxes[i]`, g a face of `tree` whose leaf box overlaps it, f != g:
/// the partial traversal of a strategy that re-checks only some faces. (smaller, larger), sorted, no duplicates.
std::vector<TrianglePair> subset_overlaps(std::span<const FaceId> subset, std::span<const Box3> subset_boxes, const TriangleBvh& tree);

}  // namespace ccd::bvh
