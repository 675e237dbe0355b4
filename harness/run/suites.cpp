/// @file
/// The built-in suites of `ccdbench run` and the labels of scenes given as files.

#include "datasets/scene_file.hpp"
#include "harness/run.hpp"

#include <nlohmann/json.hpp>

#include <map>
#include <sstream>
#include <stdexcept>

namespace ccd::harness {
namespace {

SceneSource generated(const std::string& name, std::map<std::string, double> parameters) {
  std::ostringstream label;
  label << name << "-r" << parameters.at("resolution") << "-f" << parameters.at("frames");
  if (const auto it = parameters.find("steps_per_frame"); it != parameters.end() && it->second != 1) label << "-s" << it->second;
  if (const auto it = parameters.find("obstacles"); it != parameters.end() && it->second == 1) label << "-shapes";
  if (const auto it = parameters.find("first_frame"); it != parameters.end() && it->second != 0) label << "-from" << it->second;
  return {label.str(), [name, parameters] {
            nlohmann::json block = {{"name", name}};
            for (const auto& [key, value] : parameters) block[key] = value;
            return datasets::scene_from_json({{"generator", block}}, ".", "suite scene " + name);
          }};
}

}  // namespace

std::string scene_file_label(const std::filesystem::path& path) {
  std::filesystem::path normal = path.lexically_normal();
  if (!normal.has_filename()) normal = normal.parent_path();  // "g1/" -> "g1"
  if (normal.filename() == "scene.json") normal = normal.parent_path();
  const std::string name = normal.filename().string();
  return name.empty() || name == "." || name == ".." ? std::filesystem::absolute(normal).lexically_normal().filename().string() : name;
}

std::vector<SceneSource> suite_scenes(const std::string& suite) {
  if (suite == "ci") {
    // Every cell the gate holds (scene x strategy x δ) must have colliding pairs, at the scenes' δ and at δ = 0, or
    // it gates nothing. The simulator keeps cloth about δ/2 off everything, so its scenes rarely touch at δ = 0:
    // spinning-ball does (cloth against the ball's mesh), and the kinematic fold makes real crossings of the sheet
    // with itself and with a blade, found by apccd inside its sessions as well as at their starts. The fold with
    // obstacles=shape drives a box (the blade) and a sphere through the sheet: face-shape contacts at δ = 0 too.
    return {generated("spinning-ball", {{"resolution", 8}, {"frames", 5}}), generated("fold", {{"resolution", 8}, {"frames", 24}}),
            generated("fold", {{"resolution", 8}, {"frames", 24}, {"obstacles", 1}})};
  }
  if (suite == "default") {
    // Every scene collides at its δ and at δ = 0, so that every cell of the main job (scripts/run.sh: every strategy
    // family at both) can miss something: the simulated scenes touch at δ = 0 too (drape's cloth through the
    // table's mesh between its vertices, twist and pile against themselves and each other), the flag only once it
    // folds onto itself, after its 20th frame; the kinematic fold crosses itself and its blade.
    std::vector<SceneSource> scenes;
    for (const char* name : {"spinning-ball", "drape", "twist", "funnel", "pile"}) {
      scenes.push_back(generated(name, {{"resolution", 16}, {"frames", 20}}));
    }
    scenes.insert(scenes.begin() + 2, generated("flag", {{"resolution", 16}, {"frames", 40}}));
    scenes.push_back(generated("fold", {{"resolution", 16}, {"frames", 24}}));
    return scenes;
  }
  if (suite == "paper") {
    return {generated("spinning-ball", {{"resolution", 100}, {"frames", 100}}), generated("drape", {{"resolution", 100}, {"frames", 100}}),
            generated("flag", {{"resolution", 100}, {"frames", 100}}),          generated("twist", {{"resolution", 80}, {"frames", 100}}),
            generated("funnel", {{"resolution", 100}, {"frames", 100}}),        generated("pile", {{"resolution", 64}, {"frames", 100}})};
  }
  if (suite == "large") {
    // Beyond the paper's scale: the spinning ball at about 1M triangles, frames 6-9 (3 steps of the cloth settling
    // onto the ball, contact in every step, on the order of 1e8 candidate pairs each), and frames 26-28 (2 steps of
    // resting contact, about 3e8 candidate pairs each: past the 2^32 elementary pairs a step had to keep before the
    // OpenCL backend ran a step in chunks within its memory budget), the earlier frames simulated but not written
    // (first_frame). A GPU's suite: seconds to generate on 16 cores.
    return {generated("spinning-ball", {{"resolution", 708}, {"frames", 10}, {"first_frame", 6}}),
            generated("spinning-ball", {{"resolution", 708}, {"frames", 29}, {"first_frame", 26}})};
  }
  throw std::invalid_argument("unknown suite '" + suite + "' (known: ci, default, paper, large)");
}

}  // namespace ccd::harness
