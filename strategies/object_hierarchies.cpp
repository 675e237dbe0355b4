#include "strategies/object_hierarchies.hpp"

#include <algorithm>

namespace ccd::strategies {

void ObjectHierarchies::build(const Scene& scene, std::span<const Vec3> first_frame, double inflation) {
  scene_ = &scene;
  trees_.assign(scene.objects().size(), {});
  for (ObjectId id = 0; id < scene.objects().size(); ++id) {
    const SceneObject& object = scene.object(id);
    trees_[id].build(scene.topology(), object.first_face, object.num_faces, first_frame);
    if (object.kind == ObjectKind::static_object) trees_[id].refit(scene.topology(), first_frame, first_frame, inflation);
  }
}

void ObjectHierarchies::refit(const StepView& step, double inflation) {
  for (ObjectId id = 0; id < trees_.size(); ++id) {
    if (!is_static(id)) trees_[id].refit(scene_->topology(), step.x0, step.x1, inflation);
  }
}

void ObjectHierarchies::refit(ObjectId object, std::span<const Vec3> x0, std::span<const Vec3> x1, std::span<const double> inflation) {
  trees_[object].refit(scene_->topology(), x0, x1, inflation);
}

std::vector<bvh::TrianglePair> ObjectHierarchies::candidates() const {
  std::vector<bvh::TrianglePair> self = self_candidates();
  const auto across = pair_candidates([](ObjectId, ObjectId) { return Box3(Vec3::Zero(), Vec3::Zero()); });
  if (across.empty()) return self;
  // Both lists are sorted: one merge, where a sort of the whole list was the traversal stage's serial part.
  std::vector<bvh::TrianglePair> all(self.size() + across.size());
  std::merge(self.begin(), self.end(), across.begin(), across.end(), all.begin());
  return all;
}

std::vector<bvh::TrianglePair> ObjectHierarchies::self_candidates() const {
  std::vector<bvh::TrianglePair> all;
  for (ObjectId a = 0; a < trees_.size(); ++a) {
    if (scene_->object(a).self_collision) {
      auto pairs = bvh::self_overlaps(trees_[a]);
      if (all.empty()) {
        all = std::move(pairs);  // one self-colliding object (most scenes): no copy
      } else {
        all.insert(all.end(), pairs.begin(), pairs.end());
      }
    }
  }
  return all;  // each object's pairs are sorted and object ranges ascend, so the whole is sorted
}

std::vector<bvh::TrianglePair> ObjectHierarchies::pair_candidates(const std::function<Box3(ObjectId, ObjectId)>& offset) const {
  std::vector<bvh::TrianglePair> all;
  for (const auto& [a, b] : scene_->collidable_pairs()) {
    const auto pairs = bvh::pair_overlaps(trees_[a], trees_[b], offset(a, b));
    const auto middle = all.insert(all.end(), pairs.begin(), pairs.end());
    std::inplace_merge(all.begin(), middle, all.end());  // each traversal's pairs come sorted
  }
  return all;
}

std::size_t ObjectHierarchies::bytes() const {
  std::size_t total = 0;
  for (const auto& tree : trees_) total += tree.bytes();
  return total;
}

}  // namespace ccd::strategies
