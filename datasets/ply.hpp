#pragma once
/// @file
/// PLY reader and writer: ASCII, binary little- and big-endian; float or double coordinates; any integer list
/// types for faces. Extra vertex properties and extra elements are skipped; faces must be triangles.

#include "datasets/mesh_frame.hpp"

#include <filesystem>

namespace ccd::datasets {

enum class PlyEncoding { ascii, binary_little_endian, binary_big_endian };

/// @throws InputError with the file and the line (ASCII and header) or element index (binary), for: a malformed
///         header, a missing x/y/z, a truncated body, NaN or infinite coordinates, an index out of range, a
///         repeated corner, a face that is not a triangle.
MeshFrame read_ply(const std::filesystem::path& path);

/// Writes positions as doubles (ASCII with 17 significant digits), faces as uchar-counted int lists,
/// atomically (temporary file + rename). Reading it back gives bit-identical positions.
void write_ply(const std::filesystem::path& path, const MeshFrame& frame, PlyEncoding encoding = PlyEncoding::binary_little_endian);

}  // namespace ccd::datasets
