#include "datasets/shape_json.hpp"

#include <nlohmann/json.hpp>

namespace ccd::datasets {

using nlohmann::json;

void put_shape_keys(json& object, const Shape& shape) {
  object["shape"] = std::string(to_string(shape.kind));
  if (shape.kind == ShapeKind::sphere) {
    object["radius"] = shape.radius;
  } else {
    object["half_extents"] = {shape.half_extents.x(), shape.half_extents.y(), shape.half_extents.z()};
  }
}

}  // namespace ccd::datasets
