#include "datasets/mesh_frame.hpp"

#include "core/error.hpp"
#include "datasets/obj.hpp"
#include "datasets/ply.hpp"

#include <algorithm>
#include <cctype>
#include <iostream>

namespace ccd::datasets {
namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

}  // namespace

MeshFrame read_mesh(const std::filesystem::path& path) {
  const std::string extension = lower_extension(path);
  if (extension == ".ply") return read_ply(path);
  if (extension == ".obj") return read_obj(path);
  throw InputError(path, {}, "unknown mesh format '" + extension + "' (expected .ply or .obj)");
}

void write_mesh(const std::filesystem::path& path, const MeshFrame& frame) {
  const std::string extension = lower_extension(path);
  if (extension == ".ply") return write_ply(path, frame);
  if (extension == ".obj") return write_obj(path, frame);
  throw InputError(path, {}, "unknown mesh format '" + extension + "' (expected .ply or .obj)");
}

std::size_t warn_unused_vertices(const std::filesystem::path& path, const MeshFrame& frame) {
  std::vector<bool> used(frame.positions.size(), false);
  for (const Face& face : frame.faces) {
    for (VertexId v : face) used[v] = true;
  }
  const auto unused = static_cast<std::size_t>(std::count(used.begin(), used.end(), false));
  if (unused > 0) {
    const auto first = static_cast<std::size_t>(std::find(used.begin(), used.end(), false) - used.begin());
    std::cerr << "warning: " << path.string() << ": " << unused << " vertices are used by no face (first: vertex " << first
              << "); they are not primitives and are never tested\n";
  }
  return unused;
}

}  // namespace ccd::datasets
