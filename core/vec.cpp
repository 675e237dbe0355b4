#include "core/vec.hpp"

namespace ccd {

Box3 bounding_box(std::span<const Vec3> points) {
  Box3 box;
  for (const Vec3& p : points) box.extend(p);
  return box;
}

}  // namespace ccd
