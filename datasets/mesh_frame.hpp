#pragma once
/// @file
/// One frame of one mesh as read from a file (the readers: ply.hpp, obj.hpp; by extension: mesh_file.hpp).

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

/// Counts vertices that no face uses and, when there are any, prints one warning line to stderr.
std::size_t warn_unused_vertices(const std::filesystem::path& path, const MeshFrame& frame);

}  // namespace ccd::datasets
