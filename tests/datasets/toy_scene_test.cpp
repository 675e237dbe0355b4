// A new built-in scene is one file and one line of a list (docs/DESIGN.md §9): the toy scene of toy_scene.cpp,
// linked with a scene list of the build's scenes plus its line (tests/CMakeLists.txt), is listed, resolved and
// generated like every built-in scene, with nothing else naming it.

#include "datasets/procedural_scenes.hpp"
#include "datasets/scene_file.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace ccd::datasets {
namespace {

TEST(ToyScene, TheListsLineMakesItABuiltInScene) {
  std::vector<std::string> names;
  for (const ProceduralSceneInfo& info : procedural_scenes()) names.push_back(info.name);
  const std::vector<std::string> expected = {"spinning-ball", "drape", "flag", "twist", "funnel", "pile", "fold", "toy"};
  EXPECT_EQ(names, expected);
}

TEST(ToyScene, ItsParametersResolveAsEveryScenesDo) {
  const SceneParameters resolved = resolve_scene_parameters("toy", {{"lift", 0.5}});
  EXPECT_EQ(resolved.at("lift"), 0.5);
  EXPECT_GT(resolved.count("resolution"), 0u);  // the common parameters, with_common's
  EXPECT_THROW(resolve_scene_parameters("toy", {{"wind", 1}}), std::invalid_argument);
}

TEST(ToyScene, ItGeneratesAndLoadsAsASceneFile) {
  testing::TempDir out;
  const GenerateResult result = generate_procedural_scene({"toy", {{"resolution", 5}, {"frames", 4}, {"lift", 0.5}}, out.path(), {}, {}});
  EXPECT_EQ(result.cloth_triangles, 2u * 4u * 4u);
  EXPECT_EQ(result.frames, 4u);
  SceneSequence sequence = load_scene_file(result.scene_file);
  ASSERT_EQ(sequence.num_frames(), 4u);
  // The far corner rises by `lift` over the frames; the near half stays.
  const std::vector<Vec3> first = sequence.frame(0), last = sequence.frame(3);
  EXPECT_DOUBLE_EQ(last[4].z() - first[4].z(), 0.5);
  EXPECT_DOUBLE_EQ(last[0].z(), first[0].z());
}

}  // namespace
}  // namespace ccd::datasets
