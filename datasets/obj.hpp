#pragma once
/// @file
/// Wavefront OBJ reader and writer for triangle meshes: `v x y z` and `f a b c` (also `a/t/n` forms and
/// negative, relative indices); other statements (vn, vt, g, o, s, usemtl, ...) are ignored.

#include "datasets/mesh_frame.hpp"

namespace ccd::datasets {

/// @throws InputError with file and line: malformed numbers, NaN or infinite coordinates, index 0 or out of
///         range, repeated corners, faces that are not triangles.
MeshFrame read_obj(const std::filesystem::path& path);

/// Writes `v` lines with 17 significant digits (exact round trip) and 1-based `f` lines, atomically.
void write_obj(const std::filesystem::path& path, const MeshFrame& frame);

}  // namespace ccd::datasets
