#pragma once
/// @file
/// A mesh file of either format, chosen by its extension: PLY (ply.hpp) or OBJ (obj.hpp).

#include "datasets/mesh_frame.hpp"

#include <filesystem>

namespace ccd::datasets {

/// Reads a .ply or .obj file (by extension, case-insensitive). Validates what every reader validates: at least
/// one triangle, finite coordinates, face indices in range, no repeated corner; warns on stderr about vertices no
/// face uses.
/// @throws InputError naming the file and the line or element.
MeshFrame read_mesh(const std::filesystem::path& path);

/// Writes a .ply (binary little-endian doubles) or .obj (17 significant digits: round-trips exactly) by
/// extension, atomically: to a temporary file beside `path`, renamed into place when complete.
void write_mesh(const std::filesystem::path& path, const MeshFrame& frame);

}  // namespace ccd::datasets
