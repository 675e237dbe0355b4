#include "strategies/full_traversal/full_traversal.hpp"

#include "core/assignment.hpp"
#include "strategies/elementary_tests.hpp"
#include "strategies/face_shape.hpp"
#include "strategies/object_hierarchies.hpp"

#include <stdexcept>

namespace ccd::strategies {
namespace {

class FullTraversal final : public Strategy {
 public:
  FullTraversal(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase, bool separation_filter)
      : narrow_phase_(std::move(narrow_phase)), separation_filter_(separation_filter) {}

  std::string name() const override { return "full+" + narrow_phase_->name() + (separation_filter_ ? ":filter=on" : ""); }

  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    scene_ = &scene;
    masks_ = assign_primitives(scene.topology());
    hierarchies_.build(scene, first_frame, scene.thickness() / 2);
  }

  StepResult step(const StepView& step, bool audit) override {
    StepResult result;
    {
      ScopedStageTimer timer(result.stages, "refit");
      // Half of δ on each box: two primitives within δ have overlapping boxes.
      hierarchies_.refit(step, scene_->thickness() / 2);
    }
    std::vector<bvh::TrianglePair> candidates;
    {
      ScopedStageTimer timer(result.stages, "traversal");
      candidates = hierarchies_.candidates();
    }
    run_narrow_phase(result, scene_->topology(), masks_, candidates, step, *narrow_phase_, scene_->thickness(), audit, separation_filter_);
    run_face_shape_stage(result, *scene_, step, *narrow_phase_, audit);
    result.counters.history_bytes = hierarchies_.bytes();
    return result;
  }

 private:
  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase_;
  bool separation_filter_ = false;
  const Scene* scene_ = nullptr;
  std::vector<AssignmentMask> masks_;
  ObjectHierarchies hierarchies_;
};

class BruteForce final : public Strategy {
 public:
  explicit BruteForce(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase) : narrow_phase_(std::move(narrow_phase)) {}

  std::string name() const override { return "brute+" + narrow_phase_->name(); }

  void init(const Scene& scene, std::span<const Vec3>) override {
    scene_ = &scene;
    masks_ = assign_primitives(scene.topology());
    const std::size_t faces = scene.topology().num_faces();
    if (faces > kMaxFaces) {
      throw std::invalid_argument("brute tests every triangle pair; " + std::to_string(faces) + " faces is more than its " +
                                  std::to_string(kMaxFaces) + "-face limit");
    }
    pairs_.clear();
    for (FaceId a = 0; a < faces; ++a) {
      for (FaceId b = a + 1; b < faces; ++b) {
        if (scene.may_collide(scene.object_of_face(a), scene.object_of_face(b))) pairs_.emplace_back(a, b);
      }
    }
  }

  StepResult step(const StepView& step, bool audit) override {
    StepResult result;
    run_narrow_phase(result, scene_->topology(), masks_, pairs_, step, *narrow_phase_, scene_->thickness(), audit);
    run_face_shape_stage(result, *scene_, step, *narrow_phase_, audit);
    return result;
  }

 private:
  static constexpr std::size_t kMaxFaces = 6000;
  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase_;
  const Scene* scene_ = nullptr;
  std::vector<AssignmentMask> masks_;
  std::vector<bvh::TrianglePair> pairs_;
};

}  // namespace

bool take_full_filter(std::map<std::string, std::string>& parameters) {
  const auto it = parameters.find("filter");
  if (it == parameters.end()) return false;
  const std::string value = it->second;
  parameters.erase(it);
  if (value == "on" || value == "true" || value == "1") return true;
  if (value == "off" || value == "false" || value == "0") return false;
  throw std::invalid_argument("full: filter=" + value + " must be on or off");
}

std::unique_ptr<Strategy> make_full_traversal(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase, bool separation_filter) {
  return std::make_unique<FullTraversal>(std::move(narrow_phase), separation_filter);
}

std::unique_ptr<Strategy> make_brute_force(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase) {
  return std::make_unique<BruteForce>(std::move(narrow_phase));
}

}  // namespace ccd::strategies
