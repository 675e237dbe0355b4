#include "core/error.hpp"
#include "core/scene.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

namespace ccd {
namespace {

Scene cloth_and_table(std::vector<std::pair<ObjectId, ObjectId>> collidable = {{0, 1}}) {
  return Scene({{"cloth", ObjectKind::deformable, true, 9, testing::grid_faces(3)},
                {"table", ObjectKind::static_object, false, 4, testing::tetrahedron_faces()}},
               std::move(collidable), 0.01);
}

TEST(Scene, ObjectsAreConcatenatedIntoOneGlobalNumbering) {
  const Scene scene = cloth_and_table();
  EXPECT_EQ(scene.topology().num_vertices(), 13u);
  EXPECT_EQ(scene.topology().num_faces(), 12u);
  EXPECT_EQ(scene.object(1).first_vertex, 9u);
  EXPECT_EQ(scene.object(1).first_face, 8u);
  EXPECT_EQ(scene.topology().face(8), (Face{9, 11, 10}));
  EXPECT_EQ(scene.object_of_vertex(8), 0u);
  EXPECT_EQ(scene.object_of_vertex(9), 1u);
  EXPECT_EQ(scene.object_of_face(7), 0u);
  EXPECT_EQ(scene.object_of_face(11), 1u);
  EXPECT_EQ(scene.find_object("table"), 1u);
}

TEST(Scene, CollisionFilterFollowsSelfFlagsAndCollidablePairs) {
  EXPECT_TRUE(cloth_and_table().may_collide(0, 0));
  EXPECT_FALSE(cloth_and_table().may_collide(1, 1));
  EXPECT_TRUE(cloth_and_table().may_collide(1, 0));
  EXPECT_FALSE(cloth_and_table({}).may_collide(0, 1));
}

TEST(Scene, RejectsBadDeclarations) {
  EXPECT_THROW(cloth_and_table({{0, 0}}), InputError);
  EXPECT_THROW(cloth_and_table({{0, 2}}), InputError);
  EXPECT_THROW(Scene({{"a", ObjectKind::deformable, true, 3, {{0, 1, 2}}}, {"a", ObjectKind::deformable, true, 3, {{0, 1, 2}}}},
                     {}, 0.0),
               InputError);
  EXPECT_THROW(Scene({{"a", ObjectKind::deformable, true, 3, {{0, 1, 2}}}}, {}, -1.0), InputError);
  EXPECT_THROW(cloth_and_table().with_thickness(std::nan("")), InputError);
  try {
    Scene({{"cloth", ObjectKind::deformable, true, 3, {{0, 1, 5}}}}, {}, 0.0);
    FAIL();
  } catch (const InputError& error) {
    EXPECT_EQ(error.where(), "object 'cloth', face 0");
  }
}

TEST(Scene, ObjectKindNamesRoundTrip) {
  for (ObjectKind kind : {ObjectKind::deformable, ObjectKind::rigid, ObjectKind::static_object}) {
    EXPECT_EQ(parse_object_kind(to_string(kind)), kind);
  }
  EXPECT_FALSE(parse_object_kind("solid").has_value());
}

}  // namespace
}  // namespace ccd
