#pragma once
/// @file
/// What describes a built-in procedural scene (procedural_scenes.hpp): its parameters, their values, and the
/// measurements it reports per frame. The scenes' own code (procedural/) and the generator share these.

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace ccd::datasets {

struct SceneParameter {
  std::string name;
  double default_value;
  std::string description;
  /// A parameter with named values ("obstacles": mesh, shape) holds the index of the chosen one.
  std::vector<std::string> choices = {};
};

struct ProceduralSceneInfo {
  std::string name;
  std::string description;
  /// resolution, frames and seed first, then the scene's own.
  std::vector<SceneParameter> parameters;
};

/// Parameter values by name; a missing name takes its default.
using SceneParameters = std::map<std::string, double>;

/// Per-frame measurements that show what the scene does (e.g. spinning-ball: the cloth's distance to the ball
/// and its rotation).
struct FrameReport {
  std::size_t frame = 0;
  std::vector<std::pair<std::string, double>> metrics;
};

}  // namespace ccd::datasets
