#pragma once
/// @file
/// One step of a scene: every vertex moves linearly from x0 to x1 over t in [0, 1] (docs/DESIGN.md §1).

#include "core/pair_id.hpp"
#include "core/scene.hpp"
#include "core/vec.hpp"

#include <array>
#include <span>

namespace ccd {

/// Non-owning view of step `index` (frame index -> index + 1). x0 and x1 are in the scene's global numbering and
/// have scene.topology().num_vertices() entries each.
struct StepView {
  const Scene* scene = nullptr;
  std::size_t index = 0;
  std::span<const Vec3> x0;
  std::span<const Vec3> x1;
};

/// A pair's eight positions in the query files' row order (docs/DESIGN.md §7): VF v, f0, f1, f2 at t = 0 then t = 1;
/// EE a.v0, a.v1, b.v0, b.v1 at t = 0 then t = 1.
inline std::array<Vec3, 8> pair_rows(const MeshTopology& topology, std::span<const Vec3> x0, std::span<const Vec3> x1, const VertexFacePair& p) {
  const Face& f = topology.face(p.f);
  return {x0[p.v], x0[f[0]], x0[f[1]], x0[f[2]], x1[p.v], x1[f[0]], x1[f[1]], x1[f[2]]};
}
inline std::array<Vec3, 8> pair_rows(const MeshTopology&, std::span<const Vec3> x0, std::span<const Vec3> x1, const EdgeEdgePair& p) {
  return {x0[p.a.v0], x0[p.a.v1], x0[p.b.v0], x0[p.b.v1], x1[p.a.v0], x1[p.a.v1], x1[p.b.v0], x1[p.b.v1]};
}

/// A face-shape pair's face corners and shape centre at t = 0 and t = 1 (the centre is the shape object's vertex).
inline FaceShapeRows face_shape_rows(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1, const FaceShapePair& p) {
  const Face& f = scene.topology().face(p.f);
  const VertexId c = scene.object(p.shape).first_vertex;
  return {{x0[f[0]], x0[f[1]], x0[f[2]]}, {x1[f[0]], x1[f[1]], x1[f[2]]}, x0[c], x1[c]};
}

/// Largest |x1 - x0| over the vertices (0 for none). Sizes must match.
double max_displacement(std::span<const Vec3> x0, std::span<const Vec3> x1);

}  // namespace ccd
