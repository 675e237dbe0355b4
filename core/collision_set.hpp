#pragma once
/// @file
/// The answer of a strategy or of the reference for one step: the colliding elementary pairs.

#include "core/pair_id.hpp"

#include <limits>
#include <string>
#include <vector>

namespace ccd {

/// Sentinel TOI: the method did not report a contact time.
inline constexpr double kNoToi = std::numeric_limits<double>::quiet_NaN();

/// A colliding pair and, optionally, its earliest time of impact in [0, 1] (kNoToi when not reported).
template <class Pair>
struct Contact {
  Pair pair;
  double toi = kNoToi;
};

using VertexFaceContact = Contact<VertexFacePair>;
using EdgeEdgeContact = Contact<EdgeEdgePair>;
using FaceShapeContact = Contact<FaceShapePair>;

/// Sorted, duplicate-free sets of colliding VF, EE and face-shape pairs. Add in any order and from any thread's buffer,
/// then call normalize(); duplicates keep the earliest reported TOI. Two normalized sets compare element-wise.
class CollisionSet {
 public:
  void add(VertexFacePair pair, double toi = kNoToi) { vertex_face_.push_back({pair, toi}); }
  void add(EdgeEdgePair pair, double toi = kNoToi) { edge_edge_.push_back({pair, toi}); }
  void add(FaceShapePair pair, double toi = kNoToi) { face_shape_.push_back({pair, toi}); }
  /// Appends every contact of `other` (call normalize() afterwards).
  void append(const CollisionSet& other);
  /// Sorts by pair and removes duplicates, keeping the earliest TOI of each pair.
  void normalize();
  /// Both normalized: this becomes the normalized union (a linear merge, the same set as append then normalize).
  /// Threads that normalize their own sets in parallel are then joined by merges.
  void merge_normalized(const CollisionSet& other);

  const std::vector<VertexFaceContact>& vertex_face() const { return vertex_face_; }
  const std::vector<EdgeEdgeContact>& edge_edge() const { return edge_edge_; }
  const std::vector<FaceShapeContact>& face_shape() const { return face_shape_; }
  std::size_t size() const { return vertex_face_.size() + edge_edge_.size() + face_shape_.size(); }
  bool empty() const { return size() == 0; }

  bool contains(const VertexFacePair& pair) const;
  bool contains(const EdgeEdgePair& pair) const;
  bool contains(const FaceShapePair& pair) const;

  /// Same pairs (TOIs are not compared). Both sets must be normalized.
  bool same_pairs(const CollisionSet& other) const;

 private:
  std::vector<VertexFaceContact> vertex_face_;
  std::vector<EdgeEdgeContact> edge_edge_;
  std::vector<FaceShapeContact> face_shape_;
};

/// Pairs of `a` that are not in `b` (both normalized); TOIs are those of `a`. With a = truth and b = reported
/// this is the set of misses; with a = reported and b = truth, the false alarms.
CollisionSet set_difference(const CollisionSet& a, const CollisionSet& b);

/// A 64-bit FNV-1a digest (16 hex digits) of a normalized set: every pair and the bits of its TOI, VF then EE, then
/// face-shape pairs when there are any (so sets without them keep the digests they had before shapes existed).
/// Equal sets with bit-equal TOIs give equal digests on every machine; step records carry it so that two runs can
/// be compared step by step without storing the sets (a change that should keep every answer, keeps every digest).
std::string answers_digest(const CollisionSet& set);

}  // namespace ccd
