// The built-in scenes' registry: one declaration and one entry per file of the build's list
// (procedural_scene_files.inc, generated from datasets/CMakeLists.txt by ccd_add_registry).
// Compiled on its own (not into a unity source): tests/CMakeLists.txt links a list with a toy scene added in its place
// (tests/datasets/toy_scene_test.cpp), which is what adding a scene to the build's list does.

#include "datasets/procedural/scene_setup.hpp"

namespace ccd::datasets::procedural {

#define CCD_PROCEDURAL_SCENE_FILE(file) SceneDefinition file##_scene();
#include "ccd/procedural_scene_files.inc"
#undef CCD_PROCEDURAL_SCENE_FILE

const std::vector<SceneDefinition>& scene_definitions() {
  static const std::vector<SceneDefinition> scenes = {
#define CCD_PROCEDURAL_SCENE_FILE(file) file##_scene(),
#include "ccd/procedural_scene_files.inc"
#undef CCD_PROCEDURAL_SCENE_FILE
  };
  return scenes;
}

}  // namespace ccd::datasets::procedural
