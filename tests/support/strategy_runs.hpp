#pragma once
/// @file
/// Runs a strategy over every step of a frame sequence: what the strategy tests compare.

#include "datasets/procedural_scenes.hpp"
#include "datasets/scene_file.hpp"
#include "strategies/registry.hpp"
#include "tests/support/test_support.hpp"

#include <tbb/global_control.h>

#include <string>
#include <vector>

namespace ccd::testing {

/// Each step's collision set from strategy `spec` on `threads` threads.
inline std::vector<CollisionSet> run_all_steps(const std::string& spec, const Scene& scene, const std::vector<std::vector<Vec3>>& frames,
                                               std::size_t threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  auto strategy = strategies::make_strategy(spec);
  strategy->init(scene, frames[0]);
  std::vector<CollisionSet> sets;
  for (std::size_t k = 0; k + 1 < frames.size(); ++k) {
    sets.push_back(strategy->step({&scene, k, frames[k], frames[k + 1]}, false).collisions);
  }
  return sets;
}

/// Every frame of `sequence`, in order.
inline std::vector<std::vector<Vec3>> all_frames(const datasets::SceneSequence& sequence) {
  std::vector<std::vector<Vec3>> frames;
  for (std::size_t k = 0; k < sequence.num_frames(); ++k) frames.push_back(sequence.frame(k));
  return frames;
}

/// The built-in scenes that take obstacles=shape, named "NAME:shapes" for small_scene.
inline std::vector<std::string> shape_scene_names() { return {"spinning-ball:shapes", "drape:shapes", "pile:shapes", "fold:shapes"}; }

/// The built-in scenes' names, for tests parametrized over them.
inline std::vector<std::string> procedural_scene_names() {
  std::vector<std::string> names;
  for (const auto& info : datasets::procedural_scenes()) names.push_back(info.name);
  return names;
}

struct LoadedScene {
  datasets::SceneSequence sequence;
  std::vector<std::vector<Vec3>> frames;
};

/// A built-in scene, small enough to run every strategy and the truth on every step in seconds, and long enough
/// that it collides at its own δ and at δ = 0 (tests that rely on collisions assert it; measured with
/// `ccdbench run --strategy full [--thickness 0]`: spinning-ball 1835 / 231 colliding pairs, drape 496 / 53, flag
/// 16 / 16, twist 289 / 174, funnel 1078 / 98, pile 1258 / 172, fold 1908 / 357). Heavier contact only costs time:
/// every strategy test runs under AddressSanitizer in CI too.
/// "NAME:shapes" is the scene with obstacles=shape.
inline LoadedScene small_scene(const std::string& full_name, const TempDir& dir) {
  const bool shapes = full_name.ends_with(":shapes");
  const std::string name = shapes ? full_name.substr(0, full_name.size() - 7) : full_name;
  datasets::SceneParameters parameters{{"resolution", 8}, {"frames", 12}};
  if (shapes) parameters["obstacles"] = 1;
  if (name == "pile") parameters["count"] = 2;
  if (name == "twist") {
    // The clamps need time, and a finer mat, to wind it into contact with itself.
    parameters["resolution"] = 10;
    parameters["frames"] = 24;
  }
  if (name == "flag") {
    // A coarser flag is too stiff to fold onto itself; this one first touches itself at step 33.
    parameters["resolution"] = 16;
    parameters["frames"] = 40;
  }
  if (name == "spinning-ball") parameters["frames"] = 6;  // contact from step 1 on, and a 2304-triangle ball
  if (name == "funnel") parameters["frames"] = 16;        // the cloth first touches the funnel's wall (δ = 0) in step 13
  const auto generated = datasets::generate_procedural_scene({name, parameters, dir.path(), {}, {}});
  LoadedScene loaded{datasets::load_scene_file(generated.scene_file), {}};
  loaded.frames = all_frames(loaded.sequence);
  return loaded;
}

}  // namespace ccd::testing
