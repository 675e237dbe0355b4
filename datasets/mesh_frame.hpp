#pragma once
/// @file
/// One frame of one mesh as read from a file, and the file-format dispatch (PLY or OBJ by extension).

#include "core/topology.hpp"
#include "core/vec.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace ccd::datasets {

/// Positions and faces exactly as the file lists them (vertex and face order preserved).
struct MeshFrame {
  std::vector<Vec3> positions;
  std::vector<Face> faces;
  /// What the file was, e.g. "PLY binary_little_endian (double)" or "OBJ".
  std::string format;
};

/// Reads a .ply or .obj file (by extension, case-insensitive). Validates what every reader validates: at least
/// one triangle, finite coordinates, face indices in range, no repeated corner; warns on stderr about vertices no
/// face uses.
/// @throws InputError naming the file and the line or element.
MeshFrame read_mesh(const std::filesystem::path& path);

/// Writes a .ply (binary little-endian doubles) or .obj (17 significant digits: round-trips exactly) by
/// extension, atomically: to a temporary file beside `path`, renamed into place when complete.
void write_mesh(const std::filesystem::path& path, const MeshFrame& frame);

/// Checks the rules every reader shares (finite coordinates, valid faces) and warns about unused vertices.
/// `where_vertex(i)`/`where_face(i)` give the location text for element i (e.g. its line).
/// @throws InputError attributed to `path`.
template <class WhereVertex, class WhereFace>
void validate_mesh_frame(const std::filesystem::path& path, const MeshFrame& frame, WhereVertex where_vertex, WhereFace where_face);

/// Counts vertices that no face uses and, when there are any, prints one warning line to stderr.
std::size_t warn_unused_vertices(const std::filesystem::path& path, const MeshFrame& frame);

}  // namespace ccd::datasets

#include "datasets/mesh_frame_validate.hpp"
