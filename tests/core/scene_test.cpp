#include "core/scene.hpp"
#include "core/error.hpp"
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
  EXPECT_THROW(Scene({{"a", ObjectKind::deformable, true, 3, {{0, 1, 2}}}, {"a", ObjectKind::deformable, true, 3, {{0, 1, 2}}}}, {}, 0.0),
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

// A shape object is its shape and one vertex, its centre: no faces, no self-collision; anything else is refused,
// naming the object.
TEST(Scene, ShapeObjectsAreTheirShapeAndOneCentre) {
  const Shape ball{ShapeKind::sphere, 0.5, Vec3::Zero()};
  const Shape table{ShapeKind::box, 0.0, Vec3(1, 2, 0.5)};
  const Scene scene({{"cloth", ObjectKind::deformable, true, 9, testing::grid_faces(3)},
                     {"ball", ObjectKind::shape, false, 1, {}, ball},
                     {"table", ObjectKind::shape, false, 1, {}, table}},
                    {{0, 1}, {0, 2}}, 0.0);
  EXPECT_EQ(scene.shape_objects(), (std::vector<ObjectId>{1, 2}));
  EXPECT_EQ(scene.object(1).first_vertex, 9u);
  EXPECT_EQ(scene.object(2).first_vertex, 10u);
  EXPECT_EQ(scene.object(2).shape->half_extents, Vec3(1, 2, 0.5));
  EXPECT_FALSE(scene.topology().is_used(9)) << "a centre is never a primitive";
  auto refused = [](ObjectDescription shape) { return testing::error_message<InputError>([&] { Scene({std::move(shape)}, {}, 0.0); }); };
  EXPECT_NE(refused({"ball", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::sphere, 0.0, Vec3::Zero()}}).find("radius must be finite and > 0"),
            std::string::npos);
  EXPECT_NE(refused({"ball", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::sphere, std::nan(""), Vec3::Zero()}}).find("radius"),
            std::string::npos);
  EXPECT_NE(refused({"box", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::box, 0.0, Vec3(1, 0, 1)}}).find("half extents"), std::string::npos);
  EXPECT_NE(refused({"ball", ObjectKind::shape, false, 1, {}}).find("object 'ball': an object of kind shape needs a shape"), std::string::npos);
  EXPECT_NE(refused({"ball", ObjectKind::shape, false, 3, {{0, 1, 2}}, ball}).find("one vertex, no faces"), std::string::npos);
  EXPECT_NE(refused({"ball", ObjectKind::shape, true, 1, {}, ball}).find("no self-collision"), std::string::npos);
  EXPECT_NE(refused({"cloth", ObjectKind::deformable, true, 3, {{0, 1, 2}}, ball}).find("only an object of kind shape"), std::string::npos);
}

TEST(Scene, ObjectKindNamesRoundTrip) {
  for (ObjectKind kind : {ObjectKind::deformable, ObjectKind::rigid, ObjectKind::static_object, ObjectKind::shape}) {
    EXPECT_EQ(parse_object_kind(to_string(kind)), kind);
  }
  EXPECT_FALSE(parse_object_kind("solid").has_value());
}

}  // namespace
}  // namespace ccd
