#pragma once
/// @file
/// The checks every mesh reader shares (ply.cpp, obj.cpp).

#include "core/error.hpp"
#include "datasets/mesh_frame.hpp"

#include <cmath>

namespace ccd::datasets {

/// Checks the rules every reader shares (finite coordinates, valid faces) and warns about unused vertices.
/// `where_vertex(i)`/`where_face(i)` give the location text for element i (e.g. its line).
/// @throws InputError attributed to `path`.
template <class WhereVertex, class WhereFace>
void validate_mesh_frame(const std::filesystem::path& path, const MeshFrame& frame, WhereVertex where_vertex, WhereFace where_face) {
  static constexpr const char* kAxis[3] = {"x", "y", "z"};
  // A mesh without triangles has no primitive to collide (and FCL cannot even build a model of it).
  if (frame.faces.empty()) throw InputError(path, "faces", "the mesh has no triangles (ccdbench reads triangle meshes)");
  for (std::size_t i = 0; i < frame.positions.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double value = frame.positions[i][k];
      if (!std::isfinite(value)) {
        throw InputError(
            path, where_vertex(i),
            std::string("coordinate ") + kAxis[k] + " of vertex " + std::to_string(i) + " is " + (std::isnan(value) ? "NaN" : "infinite"));
      }
    }
  }
  if (auto problem = find_face_list_problem(frame.positions.size(), frame.faces)) {
    throw InputError(path, where_face(problem->face), "face " + std::to_string(problem->face) + ": " + problem->reason);
  }
  warn_unused_vertices(path, frame);
}

}  // namespace ccd::datasets
