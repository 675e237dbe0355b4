#include "datasets/mesh_frame.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <iostream>

namespace ccd::datasets {
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
