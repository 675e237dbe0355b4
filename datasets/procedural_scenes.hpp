#pragma once
/// @file
/// The built-in procedural scenes (the paper's benchmarks as deterministic, scalable frame sequences):
/// spinning-ball, drape, flag, twist, funnel, pile, and the kinematic fold (no simulation: real crossings, for
/// gates and tests at δ = 0). Each takes a cloth resolution N (N x N vertices,
/// 2(N-1)² triangles per cloth), a frame count and a seed; the same parameters give bit-identical frames on any
/// thread count. Obstacles are triangle meshes with their own frames (a spinning ball moves, a table does not), or
/// with obstacles=shape analytic shapes (spinning-ball's sphere, drape's table and pile's ground as boxes, fold's
/// blade as a thin box and a ball driven through the sheet).

#include "datasets/scene_parameters.hpp"

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace ccd::datasets {

/// Every built-in scene with its parameters and defaults.
const std::vector<ProceduralSceneInfo>& procedural_scenes();

struct GenerateRequest {
  std::string name;
  SceneParameters parameters;
  /// The scene folder: scene.json, OBJECT/frame_%04d.ply, and cache/OBJECT.frames.
  std::filesystem::path out;
  /// (frames done, frames) during simulation.
  std::function<void(std::size_t, std::size_t)> progress;
  /// Called once per frame, in order, whether the frames were simulated or read from the cache.
  std::function<void(const FrameReport&)> report;
};

struct GenerateResult {
  std::filesystem::path scene_file;
  bool from_cache = false;
  double seconds = 0.0;
  std::size_t cloth_triangles = 0;
  std::size_t triangles = 0;
  std::size_t frames = 0;
  double thickness = 0.0;
};

/// The parameters of built-in scene `name`: defaults filled in, every value checked (what a generator block in a
/// scene file resolves to). @throws std::invalid_argument for an unknown scene or parameter, or a value out of range.
SceneParameters resolve_scene_parameters(const std::string& name, const SceneParameters& given);

/// The value of a named choice of `parameter` of scene `scene` (obstacles=shape: 1), or nullopt when it has no
/// such choice. @throws std::invalid_argument for an unknown scene.
std::optional<double> scene_parameter_choice(const std::string& scene, const std::string& parameter, const std::string& text);

/// Simulates the scene (or finds it already in `out`, generated with the same parameters) and writes its folder.
/// Two processes generating one folder take turns (a lock in the folder); the second finds it complete.
/// @throws std::invalid_argument for an unknown scene or parameter, a value out of range, a scene too large for
///         this machine's memory or the output's disk, or a simulation that diverges (naming the changed parameters).
GenerateResult generate_procedural_scene(const GenerateRequest& request);

/// Where scene files' {"generator": ...} blocks put generated scenes: CCDBENCH_CACHE_DIR, else
/// $XDG_CACHE_HOME/ccdbench, else ~/.cache/ccdbench.
std::filesystem::path procedural_cache_root();

/// Registers every built-in scene as a scene-file generator: {"generator": {"name": "flag", "wind": 12}}.

/// Generates the built-in scene `name` with `given` parameters (the rest at their defaults) into a folder of the cache
/// named by its resolved parameters, or reads the folder a same call made before. What a scene file's
/// {"generator": ...} block runs (scene_file.cpp). @throws std::invalid_argument for an unknown scene or parameter.
GenerateResult generate_cached_scene(const std::string& name, const SceneParameters& given);

}  // namespace ccd::datasets
