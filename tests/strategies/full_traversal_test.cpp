// `full` against `brute` (the independent check of culling) and against the exact truth.

#include "datasets/procedural_scenes.hpp"
#include "reference/step_truth.hpp"
#include "strategies/registry.hpp"
#include "tests/support/strategy_runs.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

namespace ccd::strategies {
namespace {

// One test per built-in scene, so that ctest spreads them over the cores.
class FullTraversalOnScene : public ::testing::TestWithParam<std::string> {};

TEST_P(FullTraversalOnScene, EqualsBruteForceForAnyThreadCountAndMissesNothing) {
  const std::string name = GetParam();
  testing::TempDir dir;
  testing::LoadedScene loaded = testing::small_scene(name, dir);
  const double scene_thickness = loaded.sequence.scene().thickness();
  for (double thickness : {0.0, scene_thickness}) {
    SCOPED_TRACE(name + ", δ = " + std::to_string(thickness));
    const Scene scene = loaded.sequence.scene().with_thickness(thickness);
    const auto brute = testing::run_all_steps("brute", scene, loaded.frames, 2);
    const auto full_one = testing::run_all_steps("full", scene, loaded.frames, 1);
    const auto full_two = testing::run_all_steps("full", scene, loaded.frames, 2);
    // filter=on drops pairs the separation filter proves apart: a subset of full's answers, still every truth pair.
    const auto filtered = testing::run_all_steps("full:filter=on", scene, loaded.frames, 2);
    std::size_t colliding = 0, face_shape = 0;
    for (std::size_t k = 0; k < brute.size(); ++k) {
      ASSERT_TRUE(full_one[k].same_pairs(brute[k])) << "step " << k << ": full " << full_one[k].size() << ", brute " << brute[k].size();
      ASSERT_TRUE(full_one[k].same_pairs(full_two[k])) << "step " << k << ": 1 and 2 threads differ";
      const auto truth = reference::compute_step_truth(scene, loaded.frames[k], loaded.frames[k + 1], {thickness, false, {}});
      const CollisionSet missed = set_difference(truth.collisions, full_one[k]);
      ASSERT_EQ(missed.size(), 0u) << "step " << k << ": full missed " << missed.size() << " of " << truth.collisions.size();
      ASSERT_EQ(set_difference(truth.collisions, filtered[k]).size(), 0u) << "step " << k << ": full:filter=on missed";
      ASSERT_EQ(set_difference(filtered[k], full_one[k]).size(), 0u) << "step " << k << ": full:filter=on reported what full did not";
      colliding += truth.collisions.size();
      face_shape += truth.collisions.face_shape().size();
    }
    EXPECT_GT(colliding, 0u) << "the scene must collide somewhere for 'misses nothing' to mean anything";
    // The simulated scenes keep cloth δ/2 off their obstacles, so at δ = 0 only the kinematic fold meets its shapes.
    if (name.ends_with(":shapes") && (thickness > 0 || name == "fold:shapes")) {
      EXPECT_GT(face_shape, 0u) << "the cloth must meet the shapes for this test to check them";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(BuiltInScenes, FullTraversalOnScene, ::testing::ValuesIn(testing::procedural_scene_names()), testing::param_name);
// Obstacles as analytic shapes: face-shape pairs beside VF and EE, each a truth pair that must not be missed.
INSTANTIATE_TEST_SUITE_P(ShapeScenes, FullTraversalOnScene, ::testing::ValuesIn(testing::shape_scene_names()), testing::param_name);

// Two triangles sharing vertex 0 whose other corners meet: the classic fold contact. Culling them for being
// adjacent would miss it (docs/DESIGN.md §1); only A = B may be skipped.
TEST(FullTraversal, FindsTheContactOfTwoTrianglesSharingAVertex) {
  const Scene scene({{"fold", ObjectKind::deformable, true, 5, {{0, 1, 2}, {0, 3, 4}}}}, {}, 0.0);
  // Triangle B swings down through triangle A's far edge (1-2) during the step.
  const std::vector<Vec3> x0 = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}, {0.4, 0.4, 1}};
  const std::vector<Vec3> x1 = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, -1}, {0.4, 0.4, -1}};
  const auto truth = reference::compute_step_truth(scene, x0, x1, {0.0, false, {}});
  ASSERT_GT(truth.collisions.size(), 0u);
  for (const char* spec : {"full", "brute"}) {
    auto strategy = make_strategy(spec);
    strategy->init(scene, x0);
    const StepResult result = strategy->step({&scene, 0, x0, x1}, true);
    EXPECT_TRUE(set_difference(truth.collisions, result.collisions).empty()) << spec;
    EXPECT_EQ(result.counters.candidate_triangle_pairs, 1u) << spec;
    // Pairs that share vertex 0 are never tested; the rest are.
    for (const auto& pair : result.tested->vertex_face) EXPECT_NE(pair.v, 0u);
  }
}

TEST(StrategyFactory, SpecsResolveAndErrorsAreClear) {
  EXPECT_EQ(make_strategy("full")->name(), "full+conservative:tolerance=1e-10:toi_tolerance=1e-06:max_iterations=20000");
  EXPECT_EQ(make_strategy("full+cubic64:eta=1e-05")->name(), "full+cubic64:eta=1e-05");
  EXPECT_EQ(make_strategy("full:filter=on")->name(), "full+conservative:tolerance=1e-10:toi_tolerance=1e-06:max_iterations=20000:filter=on");
  EXPECT_EQ(make_strategy("full:filter=off")->name(), make_strategy("full")->name());
  EXPECT_THROW(make_strategy("full:filter=maybe"), std::invalid_argument);
  EXPECT_THROW(make_strategy("brute:filter=on"), std::invalid_argument);
  EXPECT_THROW(make_strategy("fast"), std::invalid_argument);
  EXPECT_THROW(make_strategy("full+quartic"), std::invalid_argument);
  EXPECT_THROW(make_strategy("full:nf_max=3"), std::invalid_argument);
  EXPECT_THROW(make_strategy("full:oops"), std::invalid_argument);
  const std::string unknown = testing::error_message<std::invalid_argument>([] { make_strategy("full:nf_max=3"); });
  EXPECT_NE(
      unknown.find("full+conservative has no parameter 'nf_max' (full's: backend, device, device_iterations, list_start, sub_boxes, memory, filter; "
                   "narrow phase conservative's: "
                   "tolerance, toi_tolerance, max_iterations)"),
      std::string::npos)
      << unknown;
}

// Every numeric key has a range: max_iterations=1e300 used to convert to a negative count (undefined behaviour)
// and then report every query colliding.
TEST(StrategyFactory, EveryNumericKeyIsCheckedAgainstItsRange) {
  const std::string huge = testing::error_message<std::invalid_argument>([] { make_strategy("full:max_iterations=1e300"); });
  EXPECT_NE(huge.find("max_iterations=1e300 must be an integer in [1, 1e+09]"), std::string::npos) << huge;
  EXPECT_THROW(make_strategy("full:max_iterations=2.5"), std::invalid_argument);
  EXPECT_THROW(make_strategy("full:tolerance=2"), std::invalid_argument);
  EXPECT_THROW(make_strategy("full+cubic64:eta=-1e-9"), std::invalid_argument);
  EXPECT_THROW(make_strategy("full+advancement:max_iterations=0"), std::invalid_argument);
  EXPECT_EQ(make_strategy("full:max_iterations=1000000000")->name(),
            "full+conservative:tolerance=1e-10:toi_tolerance=1e-06:max_iterations=1000000000");
}

}  // namespace
}  // namespace ccd::strategies
