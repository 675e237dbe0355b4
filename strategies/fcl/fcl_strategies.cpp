/// @file
/// FCL (the Flexible Collision Library) as a peer would use it for deforming meshes (docs/DESIGN.md §3).
///
/// Both strategies keep one `fcl::BVHModel` per scene object, built once from frame 0. Each step updates a model
/// with `beginUpdateModel` / `updateSubModel` / `endUpdateModel(refit, bottom-up)`, after which its leaves bound a
/// triangle's old and new corners. Static objects are updated once at init and never again. Traversal is FCL's own:
/// `fcl::detail::selfCollide` for an object with self-collision (a model against itself, each pair of distinct
/// leaves once; identical triangles are never paired) and `fcl::detail::collide` for a collidable pair of objects.
/// FCL's traversal is sequential, so these strategies use one thread whatever `--threads` says, except for the
/// project's own narrow phase in `fcl-bvh`.
///
/// - `fcl`: FCL's `MeshContinuousCollisionTraversalNode` and its 6 VF + 9 EE cubic tests per triangle pair, with the
///   contact limit raised so that every colliding triangle pair is reported. FCL answers with triangle pairs, so the
///   strategy is judged at the triangle-pair level (Strategy::judging). Pairs of triangles that share a vertex are
///   tested like any other: FCL's own tests reject the elementary pairs that share a vertex (their four points are
///   coplanar at every t, so every coefficient of the cubic is exactly zero), and the pairs that share none are what
///   a fold contact needs.
/// - `fcl-bvh`: FCL's hierarchy and traversal as the broad phase only; its candidate triangle pairs go through the
///   project's expansion and narrow phases, so culling and elementary tests are judged apart.
///
/// FCL has no thickness and its volumes are not inflated: both refuse δ > 0 (init throws).
/// Key: `bv` = aabb | obbrss | kdop24. The default is aabb, what a peer picks for a mesh refitted every step: its
/// refit is one min/max pass (OBBRSS fits oriented boxes again: 6.2 ms against 0.23 ms per step on the default
/// suite's spinning-ball), and its boxes hold touching contacts exactly. OBBRSS is not conservative at δ = 0: on the default
/// suite's pile, fcl-bvh:bv=obbrss culled one touching edge pair of two cloths lying flat (the fitted boxes are
/// flat too, and rounding separates them).

#include "ccd/config.hpp"
#include "strategies/strategy_entry.hpp"

#include <stdexcept>

#if CCDBENCH_WITH_FCL
#include "core/assignment.hpp"
#include "strategies/elementary_tests.hpp"
#include "strategies/fcl/fcl_elementary.hpp"

// utility.h declares fcl::fit, which BVH_model-inl.h uses without including it.
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/AABB.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/math/bv/kDOP.h>
#include <fcl/math/bv/utility.h>
#include <fcl/narrowphase/detail/traversal/collision/mesh_continuous_collision_traversal_node.h>
#include <fcl/narrowphase/detail/traversal/collision_node.h>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <limits>
#endif

namespace ccd::strategies {
#if CCDBENCH_WITH_FCL
namespace {

using FclVector = fcl::Vector3<double>;

// ---------------------------------------------------------------------------------------------------------------
// One FCL model per object, in the object's local vertex and face numbering.

template <class BV>
class FclModels {
 public:
  void build(const Scene& scene, std::span<const Vec3> first_frame) {
    scene_ = &scene;
    models_.clear();
    for (ObjectId id = 0; id < scene.objects().size(); ++id) {
      const SceneObject& object = scene.object(id);
      auto model = std::make_unique<fcl::BVHModel<BV>>();
      std::vector<fcl::Triangle> triangles;
      triangles.reserve(object.num_faces);
      for (FaceId f = object.first_face; f < object.first_face + object.num_faces; ++f) {
        const Face& face = scene.topology().face(f);
        triangles.emplace_back(face[0] - object.first_vertex, face[1] - object.first_vertex, face[2] - object.first_vertex);
      }
      const auto points = local_points(object, first_frame);
      check(model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(points.size())), "beginModel");
      check(model->addSubModel(points, triangles), "addSubModel");
      check(model->endModel(), "endModel");
      // The continuous tests read the previous positions, which exist only after an update: a static object is
      // updated to where it is, once.
      update_to(*model, points);
      models_.push_back(std::move(model));
    }
  }

  /// Brings every non-static model to prev = x0, current = x1 (one update when the last step ended at x0).
  void update(const StepView& step) {
    for (ObjectId id = 0; id < models_.size(); ++id) {
      const SceneObject& object = scene_->object(id);
      if (object.kind == ObjectKind::static_object) continue;
      fcl::BVHModel<BV>& model = *models_[id];
      const auto before = step.x0.subspan(object.first_vertex, object.num_vertices);
      if (!std::equal(before.begin(), before.end(), model.vertices)) update_to(model, local_points(object, step.x0));
      update_to(model, local_points(object, step.x1));
    }
  }

  const fcl::BVHModel<BV>& model(ObjectId id) const { return *models_[id]; }

  std::size_t bytes() const {
    std::size_t total = 0;
    for (const auto& model : models_) {
      // memUsage(false) counts BVs, triangles and current vertices; the previous positions are the same size again.
      total += static_cast<std::size_t>(model->memUsage(false)) + sizeof(FclVector) * static_cast<std::size_t>(model->num_vertices);
    }
    return total;
  }

 private:
  static void check(int code, const char* call) {
    if (code != fcl::BVH_OK) throw std::runtime_error(std::string("FCL ") + call + " failed with code " + std::to_string(code));
  }

  static std::vector<FclVector> local_points(const SceneObject& object, std::span<const Vec3> positions) {
    std::vector<FclVector> points(object.num_vertices);
    for (std::size_t i = 0; i < object.num_vertices; ++i) points[i] = positions[object.first_vertex + i];
    return points;
  }

  static void update_to(fcl::BVHModel<BV>& model, const std::vector<FclVector>& points) {
    check(model.beginUpdateModel(), "beginUpdateModel");
    check(model.updateSubModel(points), "updateSubModel");
    check(model.endUpdateModel(/*refit=*/true, /*bottomup=*/true), "endUpdateModel");
  }

  const Scene* scene_ = nullptr;
  std::vector<std::unique_ptr<fcl::BVHModel<BV>>> models_;
};

/// Runs `visit(node)` over every traversal the scene asks for: self for objects with self-collision, and each
/// collidable pair; `offset_a`/`offset_b` map FCL's primitive ids back to global face ids.
template <class BV, class Node, class MakeNode, class Visit>
void for_each_traversal(const Scene& scene, const FclModels<BV>& models, MakeNode make_node, Visit visit) {
  for (ObjectId a = 0; a < scene.objects().size(); ++a) {
    if (!scene.object(a).self_collision) continue;
    Node node = make_node(models.model(a), models.model(a));
    fcl::detail::selfCollide(&node);
    visit(node, scene.object(a).first_face, scene.object(a).first_face);
  }
  for (const auto& [a, b] : scene.collidable_pairs()) {
    Node node = make_node(models.model(a), models.model(b));
    fcl::detail::collide(&node);
    visit(node, scene.object(a).first_face, scene.object(b).first_face);
  }
}

bvh::TrianglePair global_pair(FaceId first_a, int a, FaceId first_b, int b) {
  const FaceId fa = first_a + static_cast<FaceId>(a);
  const FaceId fb = first_b + static_cast<FaceId>(b);
  return {std::min(fa, fb), std::max(fa, fb)};
}

void refuse_thickness(const Scene& scene, const std::string& name) {
  if (scene.thickness() > 0) {
    throw std::invalid_argument(name +
                                " works at δ = 0 only: FCL has no thickness and its volumes are not inflated, "
                                "but this scene's δ is " +
                                std::to_string(scene.thickness()) + " (run with --thickness 0)");
  }
  // FCL's continuous collision of shapes (fcl::Sphere, fcl::Box) moves whole rigid objects; a deforming cloth
  // against them would need one rigid model per face and step, which no peer does. These baselines stay with
  // meshes: generate the scene with obstacles=mesh.
  for (const SceneObject& object : scene.objects()) {
    if (object.shape) {
      throw std::invalid_argument(name + " does not model analytic shapes: object '" + object.name + "' is a " +
                                  std::string(to_string(object.shape->kind)) + " (generate the scene with obstacles=mesh)");
    }
  }
  // FCL's endModel fails on a model without triangles (code -3): say which object instead.
  for (const SceneObject& object : scene.objects()) {
    if (object.num_faces == 0) {
      throw std::invalid_argument(name + " cannot model object '" + object.name + "': it has no triangles");
    }
  }
}

template <class Pair>
void sort_unique(std::vector<Pair>& pairs) {
  tbb::parallel_sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

// ---------------------------------------------------------------------------------------------------------------
// What both strategies do alike around their traversal.

/// An FCL strategy: it refuses what FCL cannot model (refuse_thickness), builds its models at init, refits them as
/// each step's first stage ("refit") and keeps their bytes; `detect` is the rest of its step.
template <class BV>
class FclStrategy : public Strategy {
 public:
  void check_scene(const Scene& scene) const final { refuse_thickness(scene, strategy_); }

  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    check_scene(scene);
    scene_ = &scene;
    models_.build(scene, first_frame);
  }

  StepResult step(const StepView& step, bool audit) final {
    StepResult result;
    {
      ScopedStageTimer timer(result.stages, "refit");
      models_.update(step);
    }
    detect(*scene_, models_, step, audit, result);
    result.counters.kept_bytes = models_.bytes();
    return result;
  }

 protected:
  /// `strategy`: its name in refusals ("fcl", "fcl-bvh").
  FclStrategy(std::string strategy, std::string bv_name) : strategy_(std::move(strategy)), bv_name_(std::move(bv_name)) {}

  /// The step after the refit, on models brought to it: its stages, collisions and counters (with `audit`, the
  /// tested pairs) into `result`.
  virtual void detect(const Scene& scene, const FclModels<BV>& models, const StepView& step, bool audit, StepResult& result) = 0;

  const std::string& bv_name() const { return bv_name_; }

 private:
  std::string strategy_, bv_name_;
  const Scene* scene_ = nullptr;
  FclModels<BV> models_;
};

// ---------------------------------------------------------------------------------------------------------------
// `fcl`: FCL's continuous traversal and its elementary tests.

/// FCL's node, which also lists the triangle pairs that reached its leaf test (audit mode).
template <class BV>
class AuditedContinuousNode : public fcl::detail::MeshContinuousCollisionTraversalNode<BV> {
 public:
  void leafTesting(int b1, int b2) const override {
    if (leaves) leaves->emplace_back(this->model1->getBV(b1).primitiveId(), this->model2->getBV(b2).primitiveId());
    fcl::detail::MeshContinuousCollisionTraversalNode<BV>::leafTesting(b1, b2);
  }
  std::vector<std::pair<int, int>>* leaves = nullptr;
};

template <class BV>
class FclContinuous final : public FclStrategy<BV> {
 public:
  explicit FclContinuous(std::string bv_name) : FclStrategy<BV>("fcl", std::move(bv_name)) {}

  std::string name() const override { return "fcl:bv=" + this->bv_name(); }

 private:
  void detect(const Scene& scene, const FclModels<BV>& models, const StepView&, bool audit, StepResult& result) override {
    std::vector<bvh::TrianglePair> leaves;
    std::size_t leaf_tests = 0, tests = 0;
    {
      ScopedStageTimer timer(result.stages, "traversal and tests");
      fcl::CollisionRequest<double> request;
      // canStop() ends the traversal once this many triangle pairs collide: never, here.
      request.num_max_contacts = std::numeric_limits<std::size_t>::max();
      std::vector<std::pair<int, int>> leaf_ids;
      auto make_node = [&](const fcl::BVHModel<BV>& a, const fcl::BVHModel<BV>& b) {
        AuditedContinuousNode<BV> node;
        fcl::detail::initialize(node, a, fcl::Transform3<double>::Identity(), b, fcl::Transform3<double>::Identity(), request);
        node.leaves = audit ? &leaf_ids : nullptr;
        node.enable_statistics = true;  // counters only
        return node;
      };
      auto visit = [&](const AuditedContinuousNode<BV>& node, FaceId first_a, FaceId first_b) {
        for (const auto& pair : node.pairs) result.triangle_pairs.push_back(global_pair(first_a, pair.id1, first_b, pair.id2));
        leaf_tests += static_cast<std::size_t>(node.num_leaf_tests);
        tests += static_cast<std::size_t>(node.num_vf_tests + node.num_ee_tests);
        for (const auto& [a, b] : leaf_ids) leaves.push_back(global_pair(first_a, a, first_b, b));
        leaf_ids.clear();
      };
      for_each_traversal<BV, AuditedContinuousNode<BV>>(scene, models, make_node, visit);
      sort_unique(result.triangle_pairs);
    }
    // Outside the timed stages: the elementary pairs the reported triangle pairs contain, for judging.
    TestedPairs contained;
    for (const auto& [a, b] : result.triangle_pairs) append_all_elementary_pairs(scene.topology(), a, b, contained);
    for (const VertexFacePair& pair : contained.vertex_face) result.collisions.add(pair);
    for (const EdgeEdgePair& pair : contained.edge_edge) result.collisions.add(pair);
    result.collisions.normalize();
    if (audit) {
      sort_unique(leaves);
      TestedPairs tested;
      for (const auto& [a, b] : leaves) append_all_elementary_pairs(scene.topology(), a, b, tested);
      sort_unique(tested.vertex_face);
      sort_unique(tested.edge_edge);
      result.tested = std::move(tested);
    }
    result.counters.candidate_triangle_pairs = leaf_tests;
    result.counters.elementary_tests = tests;
  }
};

// ---------------------------------------------------------------------------------------------------------------
// `fcl-bvh`: FCL's hierarchy and traversal as the broad phase only.

template <class BV>
class OverlapNode : public fcl::detail::BVHCollisionTraversalNode<BV> {
 public:
  void leafTesting(int b1, int b2) const override {
    pairs.emplace_back(this->model1->getBV(b1).primitiveId(), this->model2->getBV(b2).primitiveId());
  }
  mutable std::vector<std::pair<int, int>> pairs;
};

template <class BV>
class FclBroadPhase final : public FclStrategy<BV> {
 public:
  FclBroadPhase(std::string bv_name, std::unique_ptr<narrowphase::NarrowPhase> narrow_phase)
      : FclStrategy<BV>("fcl-bvh", std::move(bv_name)), narrow_phase_(std::move(narrow_phase)) {}

  std::string name() const override { return "fcl-bvh+" + narrow_phase_->name() + ":bv=" + this->bv_name(); }

  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    FclStrategy<BV>::init(scene, first_frame);
    masks_ = assign_primitives(scene.topology());
  }

 private:
  void detect(const Scene& scene, const FclModels<BV>& models, const StepView& step, bool audit, StepResult& result) override {
    std::vector<bvh::TrianglePair> candidates;
    {
      ScopedStageTimer timer(result.stages, "traversal");
      auto make_node = [](const fcl::BVHModel<BV>& a, const fcl::BVHModel<BV>& b) {
        OverlapNode<BV> node;
        node.model1 = &a;
        node.model2 = &b;
        return node;
      };
      auto visit = [&](const OverlapNode<BV>& node, FaceId first_a, FaceId first_b) {
        for (const auto& [a, b] : node.pairs) candidates.push_back(global_pair(first_a, a, first_b, b));
      };
      for_each_traversal<BV, OverlapNode<BV>>(scene, models, make_node, visit);
      sort_unique(candidates);
    }
    run_narrow_phase(result, scene.topology(), masks_, candidates, step, *narrow_phase_, 0.0, audit);
  }

  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase_;
  std::vector<AssignmentMask> masks_;
};

// ---------------------------------------------------------------------------------------------------------------

template <template <class> class StrategyT, class... Args>
std::unique_ptr<Strategy> with_bounding_volume(const std::string& bv, Args&&... args) {
  if (bv == "aabb") return std::make_unique<StrategyT<fcl::AABB<double>>>(bv, std::forward<Args>(args)...);
  if (bv == "obbrss") return std::make_unique<StrategyT<fcl::OBBRSS<double>>>(bv, std::forward<Args>(args)...);
  if (bv == "kdop24") return std::make_unique<StrategyT<fcl::KDOP<double, 24>>>(bv, std::forward<Args>(args)...);
  throw std::invalid_argument("unknown FCL bounding volume '" + bv + "' (known: aabb, obbrss, kdop24)");
}

}  // namespace
#endif

std::vector<StrategyEntry> fcl_strategies_entries() {
  const narrowphase::KeySpec bv = narrowphase::KeySpec::choice(
      "bv", {"aabb", "obbrss", "kdop24"}, "aabb", "FCL's bounding volume (aabb: what a peer refits every step; obbrss is not conservative at δ = 0)");
  StrategyEntry fcl;
  fcl.name = "fcl";
  fcl.help = "FCL as a peer uses it: its BVH refitted every step and its own continuous VF/EE tests (δ = 0; fcl-bvh+NARROW: ours)";
  fcl.keys = {bv};
  fcl.takes_narrow_phase = false;
  fcl.judging = Judging::triangle_pairs;
  fcl.resolve = [](const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase&) { return "fcl:bv=" + keys.choice("bv"); };
  StrategyEntry fcl_bvh;
  fcl_bvh.name = "fcl-bvh";
  fcl_bvh.resolve = [](const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase& narrow) {
    return "fcl-bvh+" + narrow.name + ":bv=" + keys.choice("bv");
  };
  fcl_bvh.help = "FCL's BVH as the broad phase, then this project's expansion and narrow phase (δ = 0)";
  fcl_bvh.keys = {bv};
#if CCDBENCH_WITH_FCL
  fcl.explain_miss = [](const narrowphase::PairRows& rows, bool vertex_face) {
    return std::string(to_string(explain_fcl_answer(rows, vertex_face)));
  };
  fcl.elementary_test = [](const narrowphase::PairRows& rows, bool vertex_face) { return vertex_face ? fcl_vertex_face(rows) : fcl_edge_edge(rows); };
  fcl.make = [](StrategyRequest request) { return with_bounding_volume<FclContinuous>(request.keys.choice("bv")); };
  fcl_bvh.make = [](StrategyRequest request) {
    return with_bounding_volume<FclBroadPhase>(request.keys.choice("bv"), std::move(request.narrow_phase));
  };
  fcl.check_scene = [](const narrowphase::SpecReader&, const Scene& scene) { refuse_thickness(scene, "fcl"); };
  fcl_bvh.check_scene = [](const narrowphase::SpecReader&, const Scene& scene) { refuse_thickness(scene, "fcl-bvh"); };
#else
  for (StrategyEntry* entry : {&fcl, &fcl_bvh}) {
    entry->unavailable = "this build has CCDBENCH_WITH_FCL=OFF (install libfcl-dev libccd-dev, which scripts/setup.sh does, and reconfigure)";
  }
#endif
  return {std::move(fcl), std::move(fcl_bvh)};
}

}  // namespace ccd::strategies
