#include "datasets/procedural/scene_setup.hpp"

#include <cmath>
#include <numbers>

namespace ccd::datasets::procedural {

std::vector<SceneParameter> with_common(std::vector<SceneParameter> own) {
  std::vector<SceneParameter> all = {{"resolution", 32, "cloth grid side N: N x N vertices, 2(N-1)^2 triangles per cloth"},
                                     {"frames", 30, "frames to generate (steps = frames - 1), 30 per simulated second"},
                                     {"seed", 1, "seed of the scene's random placement and gusts"},
                                     {"steps_per_frame", 1,
                                      "CCD steps per simulated frame: the simulator's substeps emitted as steps, simulated time "
                                      "and motion unchanged ((frames - 1) x this + 1 frames are written; 1, 2 and 4 keep the "
                                      "simulator's 4 substeps per frame bit for bit, others the next multiple)"},
                                     {"first_frame", 0,
                                      "first simulated frame written: the frames before it are simulated, not written, so a late "
                                      "stretch of a scene (its contact) costs little disk and no CCD of the fall"}};
  all.insert(all.end(), own.begin(), own.end());
  return all;
}

extern const SceneParameter kObstaclesParameter;
const SceneParameter kObstaclesParameter{
    "obstacles", 0, "mesh or shape: obstacles as triangle meshes or as analytic shapes (a sphere, a box)", {"mesh", "shape"}};

Vec3 rotate_z(const Vec3& p, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * p.x() - s * p.y(), s * p.x() + c * p.y(), p.z()};
}

double mean_edge_length(const ShapeMesh& mesh) {
  const MeshTopology topology(mesh.positions.size(), mesh.faces);
  double sum = 0.0;
  for (const Edge& e : topology.edges()) sum += (mesh.positions[e.v0] - mesh.positions[e.v1]).norm();
  return sum / static_cast<double>(topology.num_edges());
}

double thickness_of(const ShapeMesh& cloth) { return 0.05 * mean_edge_length(cloth); }

SimulatorSettings settings_for(const ShapeMesh& cloth, std::size_t n) {
  SimulatorSettings settings;
  const double spacing = (cloth.positions[1] - cloth.positions[0]).norm();
  settings.repulsion_radius = 0.6 * spacing;
  // Finer cloth needs more constraint sweeps to stay as stiff; a few more per doubling of the side.
  settings.iterations = 4 + static_cast<int>(std::log2(static_cast<double>(n)));
  return settings;
}

OutputObject cloth_object(std::string name, const ShapeMesh& mesh, std::size_t first) {
  const std::size_t count = mesh.positions.size();
  return {std::move(name), ObjectKind::deformable, true, mesh.faces, count, [first, count](const ClothSimulator& simulator, double) {
            const auto& x = simulator.positions();
            return std::vector<Vec3>(x.begin() + static_cast<std::ptrdiff_t>(first), x.begin() + static_cast<std::ptrdiff_t>(first + count));
          }};
}

OutputObject static_object(std::string name, ShapeMesh mesh) {
  const std::size_t count = mesh.positions.size();
  auto positions = mesh.positions;
  return {std::move(name), ObjectKind::static_object,
          false,           std::move(mesh.faces),
          count,           [positions](const ClothSimulator&, double) { return positions; }};
}

OutputObject shape_object(std::string name, Shape shape, std::function<Vec3(double)> centre, bool still) {
  return {std::move(name),
          ObjectKind::shape,
          false,
          {},
          1,
          [centre = std::move(centre)](const ClothSimulator&, double t) { return std::vector<Vec3>{centre(t)}; },
          shape,
          still};
}

Shape sphere_shape(double radius) { return {ShapeKind::sphere, radius, Vec3::Zero()}; }
Shape box_shape(const Vec3& half_extents) { return {ShapeKind::box, 0.0, half_extents}; }

bool shape_obstacles(const SceneParameters& p) { return p.at("obstacles") == 1.0; }

ShapeMesh placed_cloth(std::size_t n, double size, double angle, const Vec3& offset) {
  ShapeMesh cloth = cloth_grid(n, size);
  for (Vec3& p : cloth.positions) p = rotate_z(p, angle) + offset;
  return cloth;
}

double wrapped(double angle) { return std::remainder(angle, 2 * std::numbers::pi); }

}  // namespace ccd::datasets::procedural
