// Whole-step truth on small hand-made scenes, checked against brute force over every elementary pair.

#include "reference/step_truth.hpp"
#include "core/scene.hpp"
#include "core/step.hpp"
#include "reference/elementary_pair.hpp"
#include "reference/face_shape.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <random>

namespace ccd::reference {
namespace {

/// Every elementary pair the scene allows, decided exactly: the independent check of the sweep's culling.
CollisionSet brute_force_truth(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1, double delta) {
  const MeshTopology& topology = scene.topology();
  CollisionSet truth;
  for (VertexId v = 0; v < topology.num_vertices(); ++v) {
    if (!topology.is_used(v)) continue;
    for (FaceId f = 0; f < topology.num_faces(); ++f) {
      const Face& face = topology.face(f);
      if (v == face[0] || v == face[1] || v == face[2]) continue;
      if (!scene.may_collide(scene.object_of_vertex(v), scene.object_of_face(f))) continue;
      if (decide(PairKind::vertex_face, pair_rows(topology, x0, x1, VertexFacePair{v, f}), delta).collides) truth.add(VertexFacePair{v, f});
    }
  }
  for (EdgeId i = 0; i < topology.num_edges(); ++i) {
    for (EdgeId j = i + 1; j < topology.num_edges(); ++j) {
      const Edge a = topology.edge(i), b = topology.edge(j);
      if (shares_vertex(a, b)) continue;
      if (!scene.may_collide(scene.object_of_vertex(a.v0), scene.object_of_vertex(b.v0))) continue;
      if (decide(PairKind::edge_edge, pair_rows(topology, x0, x1, EdgeEdgePair{a, b}), delta).collides) {
        truth.add(make_edge_edge_pair(a, b));
      }
    }
  }
  truth.normalize();
  return truth;
}

/// A 5x5 cloth falling through a static 3x3 plate while its raised right half folds over and through its left
/// half, plus an unused vertex in the middle of everything.
struct FoldScene {
  Scene scene;
  std::vector<Vec3> x0, x1;
};

FoldScene fold_scene(bool cloth_self, bool cloth_plate) {
  std::vector<Vec3> cloth0 = testing::grid_positions(5, 1.0), cloth1 = cloth0;
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  for (std::size_t i = 0; i < cloth1.size(); ++i) {
    const double x = cloth0[i].x();
    if (x > 2) cloth0[i].z() += x - 2;
    // The left half drops to z = -0.2; the right half swings over to x -> 4 - x and ends below it, at z = -0.5.
    cloth1[i] = x > 2 ? Vec3(4 - x + jitter(random), cloth0[i].y(), -0.5) : Vec3(x, cloth0[i].y(), -0.2);
  }
  std::vector<Vec3> plate = testing::grid_positions(3, 0.0);
  for (Vec3& p : plate) p = Vec3(p.x() * 1.5 + 0.25, p.y() * 1.5 + 0.25, 0.0);
  std::vector<Vec3> x0 = cloth0, x1 = cloth1;
  x0.insert(x0.end(), plate.begin(), plate.end());
  x1.insert(x1.end(), plate.begin(), plate.end());
  x0.emplace_back(1.5, 1.5, 0.5);  // the unused vertex sits in the middle of everything
  x1.emplace_back(1.5, 1.5, -0.5);
  std::vector<std::pair<ObjectId, ObjectId>> collidable;
  if (cloth_plate) collidable.emplace_back(0, 1);
  Scene scene({{"cloth", ObjectKind::deformable, cloth_self, 25, testing::grid_faces(5)},
               {"plate", ObjectKind::static_object, false, 10, testing::grid_faces(3)}},
              collidable, 0.0);
  return {std::move(scene), std::move(x0), std::move(x1)};
}

TEST(StepTruth, EqualsBruteForceForEveryCollisionFilterAndThickness) {
  for (bool self : {true, false}) {
    for (bool inter : {true, false}) {
      for (double delta : {0.0, 0.1}) {
        SCOPED_TRACE("self " + std::to_string(self) + ", inter " + std::to_string(inter) + ", δ " + std::to_string(delta));
        FoldScene fold = fold_scene(self, inter);
        const Scene scene = fold.scene.with_thickness(delta);
        const StepTruth truth = compute_step_truth(scene, fold.x0, fold.x1, {delta, false, {}});
        const CollisionSet expected = brute_force_truth(scene, fold.x0, fold.x1, delta);
        EXPECT_TRUE(truth.collisions.same_pairs(expected)) << "sweep " << truth.collisions.size() << " pairs, brute force " << expected.size();
        if (self || inter) {
          EXPECT_GT(expected.size(), 0u) << "the scene must exercise the filter it tests";
        } else {
          EXPECT_EQ(truth.collisions.size(), 0u);
        }
      }
    }
  }
}

// Time slices only shorten the enumeration's boxes: 1, 2, 4 and 8 slices give the same pairs as brute force on
// the fold (whose swinging half moves four edge lengths, so the automatic choice slices it too), and slicing
// enumerates fewer pairs there (or it would not be worth its sweeps).
TEST(StepTruth, TimeSlicesNeverChangeTheSet) {
  for (double delta : {0.0, 0.1}) {
    FoldScene fold = fold_scene(true, true);
    const Scene scene = fold.scene.with_thickness(delta);
    const CollisionSet expected = brute_force_truth(scene, fold.x0, fold.x1, delta);
    std::size_t whole_step_pairs = 0;
    for (std::size_t slices : {1, 2, 4, 8, 0}) {
      TruthRequest request{delta, false, {}};
      request.time_slices = slices;
      const StepTruth truth = compute_step_truth(scene, fold.x0, fold.x1, request);
      EXPECT_TRUE(truth.collisions.same_pairs(expected)) << slices << " slices, δ = " << delta;
      const std::size_t enumerated = truth.statistics.vertex_face_pairs + truth.statistics.edge_edge_pairs;
      if (slices == 1) whole_step_pairs = enumerated;
      if (slices == 8) {
        EXPECT_LT(enumerated, whole_step_pairs) << "δ = " << delta;
      }
      if (slices == 0) {
        EXPECT_GT(truth.statistics.time_slices, 1u) << "the fold moves far: it should be sliced";
      }
    }
  }
}

// The plate declares 10 vertices and its 3x3 grid uses 9: vertex 25 + 9 = 34 is the unused one (this test used
// to check vertex 35, which does not exist, so it could not fail).
TEST(StepTruth, UnusedVerticesAreNeverPrimitives) {
  FoldScene fold = fold_scene(true, true);
  const VertexId unused = 34;
  ASSERT_EQ(fold.x0.size(), unused + 1u);
  ASSERT_FALSE(fold.scene.topology().is_used(unused));
  // Down through the falling left half of the cloth (z = 1 - 1.2 t there): they meet at t = 5/9.
  fold.x0[unused] = Vec3(1.5, 1.5, 2.0);
  fold.x1[unused] = Vec3(1.5, 1.5, -1.0);
  bool would_collide = false;
  for (FaceId f = 0; f < fold.scene.topology().num_faces(); ++f) {
    if (!fold.scene.may_collide(fold.scene.object_of_vertex(unused), fold.scene.object_of_face(f))) continue;
    const auto rows = pair_rows(fold.scene.topology(), fold.x0, fold.x1, VertexFacePair{unused, f});
    would_collide = would_collide || decide(PairKind::vertex_face, rows, 0.0).collides;
  }
  ASSERT_TRUE(would_collide) << "as a primitive the unused vertex would collide: else this test proves nothing";
  const StepTruth truth = compute_step_truth(fold.scene, fold.x0, fold.x1, {0.0, false, {}});
  for (const auto& contact : truth.collisions.vertex_face()) EXPECT_NE(contact.pair.v, unused);
}

/// A 6x6 cloth (jittered, seeded) falling and bending, a sphere and a box moving through it, and a second box
/// that the scene does not let collide with the cloth.
struct ShapeScene {
  Scene scene;
  std::vector<Vec3> x0, x1;
};

ShapeScene shape_scene(std::uint64_t seed, double thickness) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  std::vector<Vec3> x0 = testing::grid_positions(6, 0.0), x1 = x0;
  for (std::size_t i = 0; i < x0.size(); ++i) {
    x0[i] += Vec3(jitter(random), jitter(random), jitter(random));
    x1[i] = Vec3(x0[i].x(), x0[i].y(), -0.3 + 0.1 * std::sin(x0[i].x()) + jitter(random));
  }
  auto centre = [&](double lo, double hi) { return Vec3(std::uniform_real_distribution<double>(lo, hi)(random), 2.5, 0.0); };
  const Vec3 ball = centre(0.5, 4.5), block = centre(0.5, 4.5);
  // Ball: down through the cloth; block: up through it from below; the other box: anywhere (never collidable).
  x0.push_back(ball + Vec3(0, 0, 0.8));
  x1.push_back(ball + Vec3(0.3, 0, -0.6));
  x0.push_back(block + Vec3(0, 1, -1.2));
  x1.push_back(block + Vec3(-0.2, 1, 0.1));
  x0.push_back(Vec3(2.5, 2.5, 0));
  x1.push_back(Vec3(2.5, 2.5, 0));
  Scene scene({{"cloth", ObjectKind::deformable, true, 36, testing::grid_faces(6)},
               {"ball", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::sphere, 0.7, Vec3::Zero()}},
               {"block", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::box, 0.0, Vec3(0.6, 0.4, 0.5)}},
               {"ghost", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::box, 0.0, Vec3(9, 9, 9)}}},
              {{0, 1}, {0, 2}}, thickness);
  return {std::move(scene), std::move(x0), std::move(x1)};
}

// Face-shape pairs: the sweep's certified boxes lose none. Every face against every collidable shape, decided
// directly, is the check, on seeded scenes, at δ = 0 and δ > 0, and for every number of time slices.
TEST(StepTruth, FaceShapePairsEqualDecidingEveryFaceAgainstEveryShape) {
  std::size_t colliding = 0, spheres = 0, boxes = 0;
  for (std::uint64_t seed : {1, 2, 3}) {
    for (double delta : {0.0, 0.05}) {
      const ShapeScene s = shape_scene(seed, delta);
      CollisionSet expected;
      for (FaceId f = 0; f < s.scene.topology().num_faces(); ++f) {
        for (const ObjectId shape : s.scene.shape_objects()) {
          if (!s.scene.may_collide(0, shape)) continue;
          const FaceShapePair pair{f, shape};
          if (decide_face_shape(*s.scene.object(shape).shape, face_shape_rows(s.scene, s.x0, s.x1, pair), delta).collides) {
            expected.add(pair);
          }
        }
      }
      expected.normalize();
      for (std::size_t slices : {1, 2, 8, 0}) {
        SCOPED_TRACE("seed " + std::to_string(seed) + ", δ " + std::to_string(delta) + ", " + std::to_string(slices) + " slices");
        TruthRequest request{delta, false, {}};
        request.time_slices = slices;
        const StepTruth truth = compute_step_truth(s.scene, s.x0, s.x1, request);
        CollisionSet shape_pairs;
        for (const auto& c : truth.collisions.face_shape()) shape_pairs.add(c.pair);
        shape_pairs.normalize();
        EXPECT_TRUE(shape_pairs.same_pairs(expected)) << "sweep " << shape_pairs.size() << ", every face " << expected.size();
        EXPECT_LT(truth.statistics.face_shape_pairs, 2 * s.scene.topology().num_faces()) << "the boxes cull nothing";
      }
      colliding += expected.size();
      for (const auto& c : expected.face_shape()) (c.pair.shape == 1 ? spheres : boxes) += 1;
    }
  }
  EXPECT_GT(spheres, 0u) << "the sphere must meet the cloth for this test to mean anything";
  EXPECT_GT(boxes, 0u);
  EXPECT_LT(colliding, 6u * 2 * 2 * 50) << "not every face collides, or the boxes are not tested either";
}

TEST(StepTruth, SameSetsForOneAndTwoThreadsAndTois) {
  FoldScene fold = fold_scene(true, true);
  CollisionSet one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = compute_step_truth(fold.scene, fold.x0, fold.x1, {0.0, true, {}}).collisions;
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = compute_step_truth(fold.scene, fold.x0, fold.x1, {0.0, true, {}}).collisions;
  }
  ASSERT_TRUE(one.same_pairs(two));
  for (std::size_t i = 0; i < one.vertex_face().size(); ++i) {
    EXPECT_EQ(one.vertex_face()[i].toi, two.vertex_face()[i].toi);
    EXPECT_GE(one.vertex_face()[i].toi, 0.0);
    EXPECT_LE(one.vertex_face()[i].toi, 1.0);
  }
}

}  // namespace
}  // namespace ccd::reference
