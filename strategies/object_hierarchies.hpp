#pragma once
/// @file
/// One BVH per scene object and the traversals the scene's collision filter asks for: self traversal only for
/// objects with self-collision, object-against-object only for collidable pairs, and static objects' hierarchies
/// fitted once and never refitted (docs/DESIGN.md §3 "Model only what a scene requires").

#include "core/scene.hpp"
#include "core/step.hpp"
#include "strategies/bvh/bvh.hpp"

#include <functional>
#include <span>
#include <vector>

namespace ccd::strategies {

class ObjectHierarchies {
 public:
  /// Builds every object's tree from frame 0; static objects are fitted there, widened by `inflation`.
  void build(const Scene& scene, std::span<const Vec3> first_frame, double inflation);
  /// Refits every non-static object's tree over the step (uniform widening).
  void refit(const StepView& step, double inflation);
  /// Refits object `object` over positions x0 -> x1 (its own frame) with per-face widening (indexed by face -
  /// first face of the object).
  void refit(ObjectId object, std::span<const Vec3> x0, std::span<const Vec3> x1, std::span<const double> inflation);
  /// Grows face f's leaf box (and its ancestors) in its object's tree to hold `box`.
  void enlarge_leaf(FaceId f, const Box3& box) { trees_[scene_->object_of_face(f)].enlarge_leaf(f, box); }
  /// All candidate triangle pairs the collision filter allows, sorted.
  std::vector<bvh::TrianglePair> candidates() const;
  /// Only the self pairs of objects with self-collision, sorted.
  std::vector<bvh::TrianglePair> self_candidates() const;
  /// Only the pairs across collidable objects; `offset(a, b)` sweeps b's tree relative to a's (trees kept in
  /// moving frames). Sorted.
  std::vector<bvh::TrianglePair> pair_candidates(const std::function<Box3(ObjectId, ObjectId)>& offset) const;

  const bvh::TriangleBvh& tree(ObjectId object) const { return trees_[object]; }
  bool is_static(ObjectId object) const { return scene_->object(object).kind == ObjectKind::static_object; }
  std::size_t bytes() const;

 private:
  const Scene* scene_ = nullptr;
  std::vector<bvh::TriangleBvh> trees_;
};

}  // namespace ccd::strategies
