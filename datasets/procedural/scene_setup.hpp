#pragma once
/// @file
/// What a built-in scene is made of (datasets/procedural/<scene>.cpp, one file per scene): the objects it writes
/// and how their positions come from the simulator or from time, its collidable pairs, its thickness and its
/// per-frame measurements, plus the helpers the scenes share. procedural_scenes.cpp simulates and writes them.

#include "core/scene.hpp"
#include "core/shape.hpp"
#include "datasets/cloth_simulator.hpp"
#include "datasets/scene_parameters.hpp"
#include "datasets/shapes.hpp"

#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace ccd::datasets::procedural {

struct OutputObject {
  std::string name;
  ObjectKind kind;
  bool self_collision;
  std::vector<Face> faces;
  std::size_t num_vertices;
  /// Positions at `time`: a slice of the simulator for cloths, a function of time for obstacles (a shape's centre).
  std::function<std::vector<Vec3>(const ClothSimulator&, double)> positions;
  /// Kind shape only: the obstacle's size, and whether its centre never moves (then one frame is kept).
  std::optional<Shape> shape = std::nullopt;
  bool still = false;
};

using Metrics = std::vector<std::pair<std::string, double>>;

struct Setup {
  std::unique_ptr<ClothSimulator> simulator;
  std::vector<OutputObject> objects;
  std::vector<std::pair<std::string, std::string>> collidable;
  double thickness = 0.0;
  /// Scene-specific measurements of one frame from every object's positions (works on cached frames too).
  std::function<Metrics(std::size_t frame, double time, const std::vector<std::vector<Vec3>>& objects)> report;
};

struct CommonParameters {
  std::size_t n;
  /// Simulated frames (30 per simulated second).
  std::size_t frames;
  std::mt19937_64 random;
  /// CCD steps per simulated frame: the emitted frames are (frames - 1) · steps_per_frame + 1.
  std::size_t steps_per_frame = 1;
};

/// A built-in scene: what `ccdbench scenes` lists, and how its setup is built from the resolved parameters.
struct SceneDefinition {
  ProceduralSceneInfo info;
  Setup (*build)(CommonParameters&, const SceneParameters&);
};

/// Every built-in scene, in the order `ccdbench scenes` lists them (scene_list.cpp). The list is the build's:
/// datasets/CMakeLists.txt names one file per line, and each file procedural/FILE.cpp defines
/// `SceneDefinition FILE_scene()` in this namespace. A new built-in scene is its file and its line there.
const std::vector<SceneDefinition>& scene_definitions();

/// resolution, frames, seed and steps_per_frame, then a scene's `own` parameters.
std::vector<SceneParameter> with_common(std::vector<SceneParameter> own);
/// Obstacles as triangle meshes (the paper's) or as analytic shapes (core/shape.hpp).
extern const SceneParameter kObstaclesParameter;

Vec3 rotate_z(const Vec3& p, double angle);
double mean_edge_length(const ShapeMesh& mesh);
/// docs/DESIGN.md §1: built-in scenes declare δ as 5% of the cloth's mean rest edge length.
double thickness_of(const ShapeMesh& cloth);
/// The simulator's settings for a cloth of side n: repulsion by the spacing, more sweeps for finer cloth.
SimulatorSettings settings_for(const ShapeMesh& cloth, std::size_t n);
/// A simulated cloth: the simulator's positions first .. first + its vertices.
OutputObject cloth_object(std::string name, const ShapeMesh& mesh, std::size_t first);
/// A static mesh: the same positions in every frame.
OutputObject static_object(std::string name, ShapeMesh mesh);
/// An analytic obstacle (obstacles=shape): one vertex, its centre, at `centre(t)`.
OutputObject shape_object(std::string name, Shape shape, std::function<Vec3(double)> centre, bool still);
Shape sphere_shape(double radius);
Shape box_shape(const Vec3& half_extents);
/// obstacles=shape (1) or mesh (0, the default).
bool shape_obstacles(const SceneParameters& p);
/// Cloth grid of side `size`, rotated about z by `angle`, moved by `offset`.
ShapeMesh placed_cloth(std::size_t n, double size, double angle, const Vec3& offset);
/// `angle` in (-pi, pi].
double wrapped(double angle);

}  // namespace ccd::datasets::procedural
