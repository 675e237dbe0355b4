#include "datasets/scene_file.hpp"
#include "core/error.hpp"
#include "datasets/mesh_file.hpp"
#include "datasets/mesh_frame.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

namespace ccd::datasets {
namespace {

using testing::TempDir;
using testing::write_text;

/// A cloth (3 frames, pattern), a static table (one file) and a ball (3 frames, list of files).
void write_three_object_scene(const TempDir& dir, const std::string& scene_json) {
  for (int k = 0; k < 3; ++k) {
    write_mesh(dir / ("cloth/frame_000" + std::to_string(k) + ".ply"), {testing::grid_positions(3, 1.0 - 0.1 * k), testing::grid_faces(3), ""});
    write_mesh(dir / ("ball" + std::to_string(k) + ".obj"), {{{0, 0, 2}, {1, 0, 2}, {0, 1, 2}, {0, 0, 3.0 + k}}, testing::tetrahedron_faces(), ""});
  }
  write_mesh(dir / "table.obj", {testing::grid_positions(2), testing::grid_faces(2), ""});
  write_text(dir / "scene.json", scene_json);
}

const char* kScene = R"({
  "name": "three",
  "thickness": 0.05,
  "objects": [
    {"name": "cloth", "frames": {"pattern": "cloth/frame_%04d.ply"}},
    {"name": "table", "kind": "static", "frames": {"files": ["table.obj"]}},
    {"name": "ball", "kind": "rigid", "frames": {"files": ["ball0.obj", "ball1.obj", "ball2.obj"]}}
  ],
  "collidable": [["cloth", "table"], ["ball", "cloth"]]
})";

TEST(SceneFile, LoadsObjectsKindsFlagsPairsAndFrames) {
  TempDir dir;
  write_three_object_scene(dir, kScene);
  const SceneSequence sequence = load_scene_file(dir.path());
  const Scene& scene = sequence.scene();
  ASSERT_EQ(scene.objects().size(), 3u);
  EXPECT_EQ(scene.thickness(), 0.05);
  EXPECT_TRUE(scene.object(0).self_collision);
  EXPECT_EQ(scene.object(1).kind, ObjectKind::static_object);
  EXPECT_FALSE(scene.object(1).self_collision);
  EXPECT_EQ(scene.object(2).kind, ObjectKind::rigid);
  EXPECT_TRUE(scene.may_collide(0, 1));
  EXPECT_TRUE(scene.may_collide(2, 0));
  EXPECT_FALSE(scene.may_collide(1, 2));
  EXPECT_EQ(sequence.num_frames(), 3u);
  const auto frame = sequence.frame(2);
  EXPECT_EQ(frame.size(), 9u + 4u + 4u);
  EXPECT_DOUBLE_EQ(frame[0].z(), 0.8);
  EXPECT_EQ(frame[9 + 4 + 3].z(), 5.0);
}

TEST(SceneFile, CollidableDefaultsToEveryPair) {
  TempDir dir;
  nlohmann::json scene = nlohmann::json::parse(kScene);
  scene.erase("collidable");
  write_three_object_scene(dir, scene.dump());
  EXPECT_EQ(load_scene_file(dir / "scene.json").scene().collidable_pairs().size(), 3u);
}

std::string scene_error(const std::string& scene_json, bool moving_table = false) {
  TempDir dir;
  write_three_object_scene(dir, scene_json);
  if (moving_table) write_mesh(dir / "table1.obj", {testing::grid_positions(2, 0.5), testing::grid_faces(2), ""});
  try {
    const SceneSequence sequence = load_scene_file(dir.path());
    for (std::size_t k = 0; k < sequence.num_frames(); ++k) sequence.frame(k);
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

std::string with_change(const std::function<void(nlohmann::json&)>& change) {
  nlohmann::json scene = nlohmann::json::parse(kScene);
  change(scene);
  return scene.dump(2);
}

TEST(SceneFileBadInput, EachMistakeIsNamed) {
  EXPECT_NE(scene_error("{\n  \"objects\": [\n  oops\n]}").find("line 3"), std::string::npos);
  EXPECT_NE(scene_error(with_change([](auto& s) { s["objects"][0]["self_colision"] = true; })).find("objects[0]: unknown key 'self_colision'"),
            std::string::npos);
  EXPECT_NE(scene_error(with_change([](auto& s) { s["objects"][1]["kind"] = "solid"; })).find("unknown kind 'solid'"), std::string::npos);
  EXPECT_NE(scene_error(with_change([](auto& s) { s["collidable"][0][1] = "floor"; })).find("no object named 'floor'"), std::string::npos);
  EXPECT_NE(scene_error(with_change([](auto& s) { s["thickness"] = -1; })).find("thickness"), std::string::npos);
  EXPECT_NE(scene_error(with_change([](auto& s) {
              s["objects"][0]["frames"] = {{"files", {"missing.ply"}}};
            })).find("missing.ply"),
            std::string::npos);
  EXPECT_NE(scene_error(with_change([](auto& s) {
              s["objects"][2]["frames"]["files"] = {"ball0.obj", "ball1.obj"};
            })).find("has 2 frames"),
            std::string::npos);
  EXPECT_NE(scene_error(with_change([](auto& s) {
                          s["objects"][1]["frames"]["files"] = {"table.obj", "table.obj", "table1.obj"};
                        }),
                        true)
                .find("a static object must not move"),
            std::string::npos);
}

// Shapes: a sphere with a track of centres (one per frame) and a still box (one centre); their centres are the
// frames' last vertices, and every mistake is named by its key.
TEST(SceneFile, ShapeObjectsWithTracks) {
  nlohmann::json scene = nlohmann::json::parse(kScene);
  scene["objects"][2] = {
      {"name", "ball"}, {"kind", "shape"}, {"shape", "sphere"}, {"radius", 0.25}, {"track", {{"centres", {{0, 0, 1}, {0, 0, 0.5}, {0, 0, 0.125}}}}}};
  scene["objects"].push_back(
      {{"name", "block"}, {"kind", "shape"}, {"shape", "box"}, {"half_extents", {1, 2, 0.5}}, {"track", {{"centres", {{3, 3, 3}}}}}});
  scene["collidable"].push_back({"block", "cloth"});
  {
    TempDir dir;
    write_three_object_scene(dir, scene.dump());
    const SceneSequence sequence = load_scene_file(dir.path());
    const Scene& s = sequence.scene();
    ASSERT_EQ(s.shape_objects(), (std::vector<ObjectId>{2, 3}));
    EXPECT_EQ(s.object(2).shape->radius, 0.25);
    EXPECT_EQ(s.object(3).shape->half_extents, Vec3(1, 2, 0.5));
    EXPECT_FALSE(s.object(2).self_collision);
    const auto frame = sequence.frame(2);
    ASSERT_EQ(frame.size(), 9u + 4u + 1u + 1u);
    EXPECT_EQ(frame[13], Vec3(0, 0, 0.125));
    EXPECT_EQ(frame[14], Vec3(3, 3, 3)) << "one centre holds the box still";
  }
  auto changed = [&](const std::function<void(nlohmann::json&)>& change) {
    nlohmann::json s = scene;
    change(s);
    return scene_error(s.dump(2));
  };
  EXPECT_NE(changed([](auto& s) { s["objects"][2]["radius"] = -1; }).find("objects[2]: a sphere's radius must be finite and > 0"), std::string::npos);
  EXPECT_NE(changed([](auto& s) { s["objects"][2]["shape"] = "cone"; }).find("objects[2].shape: unknown shape 'cone'"), std::string::npos);
  EXPECT_NE(changed([](auto& s) {
              s["objects"][3]["half_extents"] = {1, 2};
            }).find("objects[3].half_extents: must be an array of three"),
            std::string::npos);
  EXPECT_NE(changed([](auto& s) { s["objects"][3]["radius"] = 1; }).find("objects[3].radius: a box has half extents"), std::string::npos);
  EXPECT_NE(changed([](auto& s) { s["objects"][2]["frames"] = s["objects"][0]["frames"]; }).find("objects[2]: unknown key 'frames'"),
            std::string::npos);
  EXPECT_NE(changed([](auto& s) { s["objects"][2].erase("track"); }).find("objects[2]: missing key 'track'"), std::string::npos);
  EXPECT_NE(changed([](auto& s) {
              s["objects"][2]["track"]["centres"][1] = {0, "x", 0};
            }).find("objects[2].track.centres[1]: must be an array of three numbers"),
            std::string::npos);
  EXPECT_NE(changed([](auto& s) { s["objects"][2]["track"]["centres"] = {{0, 0, 1}, {0, 0, 1}}; }).find("has 2 frames"), std::string::npos);
  EXPECT_NE(changed([](auto& s) { s["objects"][2]["track"] = {{"cache", "missing.frames"}}; }).find("missing.frames"), std::string::npos);
}

TEST(SceneFile, GeneratorsAreLookedUpByName) {
  EXPECT_NE(scene_error(R"({"generator": {"name": "no-such-scene"}})").find("unknown scene generator 'no-such-scene'"), std::string::npos);
  TempDir dir;
  register_scene_generator("test-single-triangle", [&dir](const nlohmann::json& parameters, const std::filesystem::path&) {
    const double z = parameters.at("z").get<double>();
    write_mesh(dir / "t.obj", {{{0, 0, z}, {1, 0, z}, {0, 1, z}}, {{0, 1, 2}}, ""});
    return scene_from_frame_files({dir / "t.obj"}, 0.0);
  });
  write_text(dir / "gen.json", R"({"thickness": 0.25, "generator": {"name": "test-single-triangle", "z": 7}})");
  const SceneSequence sequence = load_scene_file(dir / "gen.json");
  EXPECT_EQ(sequence.scene().thickness(), 0.25);
  EXPECT_EQ(sequence.frame(0)[2].z(), 7.0);
}

}  // namespace
}  // namespace ccd::datasets
