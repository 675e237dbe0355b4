#include "datasets/mesh_file.hpp"

#include "core/error.hpp"
#include "datasets/obj.hpp"
#include "datasets/ply.hpp"

#include <algorithm>
#include <cctype>
#include <string>

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

}  // namespace ccd::datasets
