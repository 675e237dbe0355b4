// A toy built-in scene, added the way any built-in scene is (datasets/procedural/scene_setup.hpp): this file, which
// defines `SceneDefinition toy_scene()`, and its line in a scene list (tests/CMakeLists.txt, toy_scene_tests). Nothing
// else names it. Kinematic: a sheet whose right half lifts and swings over its left half.

#include "datasets/procedural/scene_setup.hpp"

#include <cmath>

namespace ccd::datasets::procedural {
namespace {

Setup toy(CommonParameters& c, const SceneParameters& p) {
  const double lift = p.at("lift");
  ShapeMesh sheet = cloth_grid(c.n, 1.0);
  const double last_time = static_cast<double>(c.frames - 1) * SimulatorSettings{}.frame_seconds;
  Setup setup;
  setup.thickness = thickness_of(sheet);
  setup.simulator = std::make_unique<ClothSimulator>(SimulatorSettings{});  // nothing to simulate
  setup.objects.push_back({"sheet", ObjectKind::deformable, true, sheet.faces, sheet.positions.size(),
                           [rest = sheet.positions, lift, last_time](const ClothSimulator&, double t) {
                             std::vector<Vec3> x = rest;
                             for (Vec3& v : x) {
                               if (v.x() > 0) v.z() += lift * 2 * v.x() * t / last_time;  // the far edge, x = 0.5, by `lift`
                             }
                             return x;
                           }});
  setup.report = [lift, last_time](std::size_t, double t, const std::vector<std::vector<Vec3>>&) { return Metrics{{"lift", lift * t / last_time}}; };
  return setup;
}

}  // namespace

SceneDefinition toy_scene() {
  return {{"toy", "a test's toy: the right half of a sheet lifts", with_common({{"lift", 0.25, "how far the far edge lifts (m)"}})}, toy};
}

}  // namespace ccd::datasets::procedural
