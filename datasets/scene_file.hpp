#pragma once
/// @file
/// Scene files (JSON): declare only what a scene needs (docs/DESIGN.md §1 "Scenes").
///
///     {
///       "name": "cloth-on-table",
///       "thickness": 0.001,                       // δ >= 0, scene units; default 0
///       "objects": [
///         {"name": "cloth", "kind": "deformable",  // deformable | rigid | static
///          "self_collision": true,                 // default: true for deformable, false otherwise
///          "frames": {"pattern": "cloth/frame_%04d.ply"}},
///         {"name": "table", "kind": "static", "frames": {"files": ["table.obj"]}},
///         {"name": "ball", "kind": "shape", "shape": "sphere", "radius": 0.5,   // or "shape": "box",
///          "track": {"centres": [[0, 0, 0.5], [0, 0, 0.49]]}}                  //   "half_extents": [X, Y, Z]
///       ],
///       "collidable": [["cloth", "table"]]        // object pairs that may collide; default: every pair
///     }
///
/// "frames" is exactly one of: {"files": [...]}, {"pattern": "printf pattern"}, {"directory": "dir"},
/// {"cache": "file.frames"} (a frame cache, frame_cache.hpp). Relative paths are relative to the scene file.
/// An object of kind "shape" is an analytic obstacle (core/shape.hpp): a sphere or an axis-aligned box with a
/// "track" instead of "frames", its centre per frame ({"centres": [...]}, one centre for a still shape, or
/// {"cache": "file.frames"} of one vertex and no faces). A shape has no self-collision.
/// Instead of "objects", a scene may name a generator: {"generator": {"name": "...", ...parameters}} (procedural
/// scenes register themselves; see register_scene_generator). Unknown keys are errors, so a typo never passes
/// silently.

#include "datasets/scene_sequence.hpp"

#include <nlohmann/json_fwd.hpp>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace ccd::datasets {

/// Reads a scene file, or a directory holding `scene.json`.
/// @throws InputError naming the file and the JSON location (line, or key path like "objects[1].frames").
SceneSequence load_scene_file(const std::filesystem::path& path);

/// Builds a scene from a parsed scene-file document; `base` resolves relative paths; `file` names errors.
SceneSequence scene_from_json(const nlohmann::json& document, const std::filesystem::path& base, const std::filesystem::path& file);

/// A procedural scene: builds a whole scene (every object and its frames) from a generator block's parameters.
/// @param parameters the generator block without "name"
/// @param file       the scene file, for error messages
using SceneGeneratorFunction = std::function<SceneSequence(const nlohmann::json& parameters, const std::filesystem::path& file)>;

/// Makes `name` usable as {"generator": {"name": name, ...}}. Registering a name twice replaces it.
void register_scene_generator(const std::string& name, SceneGeneratorFunction generator);
/// Registered generator names, sorted.
std::vector<std::string> scene_generator_names();

}  // namespace ccd::datasets
