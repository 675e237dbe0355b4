// The FCL baselines: fcl-bvh's broad phase loses nothing at δ = 0, fcl is judged by triangle pairs, both refuse
// δ > 0, and every query of the FCL regression library reproduces the miss its file is named after.

#include "datasets/query_file.hpp"
#include "reference/elementary_pair.hpp"
#include "reference/step_truth.hpp"
#include "strategies/fcl/fcl_elementary.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "strategies/registry.hpp"
#include "tests/support/strategy_runs.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <iostream>

#include <algorithm>
#include <set>

namespace ccd::strategies {
namespace {

template <class Pair>
bool contains_sorted(const std::vector<Pair>& pairs, const Pair& pair) {
  return std::binary_search(pairs.begin(), pairs.end(), pair);
}

class FclBvhOnScene : public ::testing::TestWithParam<std::string> {};

TEST_P(FclBvhOnScene, CandidatesCoverEveryTruthPairAndNothingIsMissed) {
  const std::string name = GetParam();
  testing::TempDir dir;
  const testing::LoadedScene loaded = testing::small_scene(name, dir);
  const Scene scene = loaded.sequence.scene().with_thickness(0.0);
  std::size_t colliding = 0;
  std::vector<CollisionSet> truth;
  for (std::size_t k = 0; k + 1 < loaded.frames.size(); ++k) {
    truth.push_back(reference::compute_step_truth(scene, loaded.frames[k], loaded.frames[k + 1], {0.0, false, {}}).collisions);
    colliding += truth.back().size();
  }
  // aabb and kdop24 contain the swept triangles and cull nothing. obbrss does cull touching pairs (flat cloths get
  // flat oriented boxes that rounding separates: reports/fcl/MISSES.md), so it is only counted here.
  for (const char* bv : {"aabb", "obbrss", "kdop24"}) {
    SCOPED_TRACE(name + " with " + bv);
    const bool conservative = std::string(bv) != "obbrss";
    auto strategy = make_strategy(std::string("fcl-bvh:bv=") + bv);
    strategy->init(scene, loaded.frames[0]);
    std::size_t culled = 0;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      const StepResult result = strategy->step({&scene, k, loaded.frames[k], loaded.frames[k + 1]}, true);
      // Tested pairs come from the candidate triangle pairs only, so a truth pair among them was not culled.
      for (const auto& c : truth[k].vertex_face()) {
        const bool tested = contains_sorted(result.tested->vertex_face, c.pair);
        culled += tested ? 0 : 1;
        if (conservative) {
          ASSERT_TRUE(tested) << "step " << k << ": VF " << c.pair.v << "/" << c.pair.f << " culled";
        }
      }
      for (const auto& c : truth[k].edge_edge()) {
        const bool tested = contains_sorted(result.tested->edge_edge, c.pair);
        culled += tested ? 0 : 1;
        if (conservative) {
          ASSERT_TRUE(tested) << "step " << k << ": an EE pair culled";
        }
      }
      if (conservative) {
        ASSERT_EQ(set_difference(truth[k], result.collisions).size(), 0u) << "step " << k;
      }
    }
    if (!conservative) std::cout << name << ": fcl-bvh:bv=obbrss culled " << culled << " colliding pairs\n";
  }
  EXPECT_GT(colliding, 0u) << name << " must collide at δ = 0 to test this";
}

INSTANTIATE_TEST_SUITE_P(BuiltInScenes, FclBvhOnScene, ::testing::ValuesIn(testing::procedural_scene_names()), testing::param_name);

// The fold contact of two triangles sharing vertex 0 (as in full_traversal_test): FCL's own tests reject the pairs
// that share the vertex (their cubic is identically zero) and find the others, so `fcl` reports the triangle pair.
TEST(Fcl, ReportsTheFoldContactOfTrianglesSharingAVertexJudgedByTrianglePairs) {
  const Scene scene({{"fold", ObjectKind::deformable, true, 5, {{0, 1, 2}, {0, 3, 4}}}}, {}, 0.0);
  const std::vector<Vec3> x0 = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}, {0.4, 0.4, 1}};
  const std::vector<Vec3> x1 = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, -1}, {0.4, 0.4, -1}};
  const auto truth = reference::compute_step_truth(scene, x0, x1, {0.0, false, {}});
  ASSERT_GT(truth.collisions.size(), 0u);
  for (const char* bv : {"aabb", "obbrss", "kdop24"}) {
    auto strategy = make_strategy(std::string("fcl:bv=") + bv);
    EXPECT_EQ(strategy_entry_of(strategy->name()).judging, Judging::triangle_pairs);
    strategy->init(scene, x0);
    const StepResult result = strategy->step({&scene, 0, x0, x1}, true);
    ASSERT_EQ(result.triangle_pairs, (std::vector<bvh::TrianglePair>{{0, 1}})) << bv;
    EXPECT_TRUE(set_difference(truth.collisions, result.collisions).empty()) << bv;
    // Every elementary pair of the triangle pair counts as reported, none sharing vertex 0.
    for (const auto& c : result.collisions.vertex_face()) EXPECT_NE(c.pair.v, 0u);
  }
}

TEST(Fcl, ThicknessUnknownVolumesAndNarrowPhasesAreClearErrors) {
  const Scene thick({{"cloth", ObjectKind::deformable, true, 3, {{0, 1, 2}}}}, {}, 0.01);
  const std::vector<Vec3> x = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (const char* spec : {"fcl", "fcl-bvh", "fcl-bvh+cubic64:bv=aabb"}) {
    auto strategy = make_strategy(spec);
    const std::string message = testing::error_message<std::invalid_argument>([&] { strategy->init(thick, x); });
    EXPECT_NE(message.find("δ = 0 only"), std::string::npos) << message;
    EXPECT_NE(message.find("--thickness 0"), std::string::npos) << message;
  }
  const std::string unknown = testing::error_message<std::invalid_argument>([] { make_strategy("fcl:bv=sphere"); });
  EXPECT_NE(unknown.find("aabb, obbrss or kdop24"), std::string::npos) << unknown;
  EXPECT_THROW(make_strategy("fcl-bvh:bv=obb"), std::invalid_argument);
  EXPECT_THROW(make_strategy("fcl+cubic64"), std::invalid_argument);
  EXPECT_THROW(make_strategy("fcl:tolerance=1"), std::invalid_argument);
  EXPECT_EQ(make_strategy("fcl")->name(), "fcl:bv=aabb");
  EXPECT_EQ(make_strategy("fcl-bvh+cubic64:bv=kdop24")->name(), "fcl-bvh+cubic64:eta=1e-06:bv=kdop24");
}

// FCL's endModel fails on a model without triangles (it used to surface as "FCL endModel failed with code -3").
TEST(Fcl, AnObjectWithoutTrianglesIsRefusedByName) {
  const Scene scene({{"cloth", ObjectKind::deformable, true, 3, {{0, 1, 2}}}, {"points", ObjectKind::static_object, false, 2, {}}}, {{0, 1}}, 0.0);
  for (const char* spec : {"fcl", "fcl-bvh"}) {
    const std::string message = testing::error_message<std::invalid_argument>([&] { make_strategy(spec)->check_scene(scene); });
    EXPECT_NE(message.find("cannot model object 'points': it has no triangles"), std::string::npos) << message;
  }
}

// tests/regression/fcl/KIND/CAUSE.csv: pairs from the default suite that collide (exact) and that FCL's own test
// misses, one per cause (strategies/fcl/fcl_elementary.hpp). Each must still collide, still be missed by FCL for
// that cause, and be found by the conservative narrow phase.
TEST(FclRegression, EachQueryCollidesAndFclMissesItForTheCauseItIsFiledUnder) {
  const auto files = datasets::discover_query_files({"tests/regression/fcl"});
  ASSERT_GE(files.size(), 4u);
  const auto conservative = narrowphase::make_narrow_phase("conservative");
  std::set<std::string> causes;
  for (const auto& path : files) {
    const datasets::QueryFile file = datasets::read_query_file(path);
    const bool vertex_face = file.kind == datasets::QueryKind::vertex_face;
    const std::string cause = path.stem().string();
    causes.insert(cause);
    for (const datasets::Query& query : file.queries) {
      SCOPED_TRACE(path.string() + ":" + std::to_string(query.first_line));
      reference::ExactPair pair;
      pair.kind = vertex_face ? reference::PairKind::vertex_face : reference::PairKind::edge_edge;
      pair.rows = query.exact;
      EXPECT_TRUE(reference::decide(pair, mpq_class(0)).collides);
      EXPECT_EQ(vertex_face ? fcl_vertex_face(query.rounded) : fcl_edge_edge(query.rounded), false);
      EXPECT_EQ(to_string(explain_fcl_answer(query.rounded, vertex_face)), cause);
      const auto found = vertex_face ? conservative->vertex_face(query.rounded, 0.0) : conservative->edge_edge(query.rounded, 0.0);
      EXPECT_TRUE(found.collides);
    }
  }
  EXPECT_EQ(causes, (std::set<std::string>{"coplanar-motion", "near-zero-cubic", "parallel-threshold", "root-rejected"}));
}

// The absolute constants make FCL's answer depend on units: the same crossing, scaled by a power of two (exact),
// is found at metre scale and lost at millimetre-sized features.
TEST(Fcl, AnswerDependsOnTheSceneUnits) {
  narrowphase::PairRows rows = {Vec3(0.3, 0.3, 1),  Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0),
                                Vec3(0.3, 0.3, -1), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  EXPECT_TRUE(fcl_vertex_face(rows));
  for (Vec3& row : rows) row *= 0x1p-10;  // about a millimetre
  EXPECT_FALSE(fcl_vertex_face(rows));
  EXPECT_EQ(explain_fcl_answer(rows, true), FclMissCause::near_zero_cubic);
}

}  // namespace
}  // namespace ccd::strategies
