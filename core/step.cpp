#include "core/step.hpp"

#include <algorithm>
#include <cassert>

namespace ccd {

double max_displacement(std::span<const Vec3> x0, std::span<const Vec3> x1) {
  assert(x0.size() == x1.size());
  double largest = 0.0;
  for (std::size_t i = 0; i < x0.size(); ++i) largest = std::max(largest, (x1[i] - x0[i]).norm());
  return largest;
}

}  // namespace ccd
