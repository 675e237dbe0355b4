#pragma once
/// @file
/// One step of a scene: every vertex moves linearly from x0 to x1 over t in [0, 1] (DESIGN.md §1).

#include "core/scene.hpp"
#include "core/vec.hpp"

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

/// Largest |x1 - x0| over the vertices (0 for none). Sizes must match.
double max_displacement(std::span<const Vec3> x0, std::span<const Vec3> x1);

}  // namespace ccd
