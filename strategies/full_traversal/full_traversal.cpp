/// @file
/// `full`: the baseline APCCD is measured against. Every step: refit every deformable object's BVH over the
/// swept, δ-inflated triangle boxes, traverse fully (self and object pairs as the scene declares), expand the
/// candidates by the assignment masks and run the narrow phase on every elementary pair.
/// With filter=on (`separation_filter`), the separation filter apccd's front end uses (separation_filter.hpp) drops
/// the elementary pairs it proves apart before the narrow phase: the baseline that splits apccd's gain into what
/// the filter gives and what its sessions give. Its name then ends in ":filter=on" (off, the default, is not
/// printed, so that the names of existing results stay).
/// `brute`: every triangle pair the scene lets collide, no culling at all (small scenes): the independent check
/// of culling.

#include "core/assignment.hpp"
#include "strategies/backend.hpp"
#include "strategies/elementary_tests.hpp"
#include "strategies/face_shape.hpp"
#include "strategies/object_hierarchies.hpp"
#include "strategies/opencl/full_opencl.hpp"
#include "strategies/strategy_entry.hpp"

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
    result.counters.kept_bytes = hierarchies_.bytes();
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

std::vector<StrategyEntry> full_traversal_entries() {
  StrategyEntry full;
  full.name = "full";
  full.help = "BVH refit over swept, δ-inflated triangle boxes and a full traversal every step: the baseline";
  full.keys = backend_keys();
  full.keys.push_back(narrowphase::KeySpec::on_off("filter", false, "apccd's separation filter before the narrow phase (splits apccd's gain)"));
  full.backends = {"cpu", "opencl"};
  full.make = [](StrategyRequest request) -> std::unique_ptr<Strategy> {
    const bool filter = request.keys.choice("filter") == "on";
    const BackendChoice backend = read_backend(request.keys);
    if (backend.opencl()) return make_full_opencl(std::move(request.narrow_phase), backend, filter);
    return std::make_unique<FullTraversal>(std::move(request.narrow_phase), filter);
  };
  full.check = [](const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase& narrow) {
    resolved_backend("full", read_backend(keys), narrow, false);
  };
  full.resolve = [](const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase& narrow) {
    const BackendChoice backend = read_backend(keys);
    return "full+" + narrow.name + (keys.choice("filter") == "on" ? ":filter=on" : "") + resolved_backend("full", backend, narrow, false);
  };
  StrategyEntry brute;
  brute.name = "brute";
  brute.help = "every triangle pair the scene lets collide, no culling (small scenes): the independent check of culling";
  brute.make = [](StrategyRequest request) -> std::unique_ptr<Strategy> { return std::make_unique<BruteForce>(std::move(request.narrow_phase)); };
  brute.resolve = [](const narrowphase::SpecReader&, const narrowphase::ResolvedNarrowPhase& narrow) { return "brute+" + narrow.name; };
  return {std::move(full), std::move(brute)};
}

}  // namespace ccd::strategies
