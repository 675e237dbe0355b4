#pragma once
/// @file
/// An analytic shape's keys as scene files hold them (scene_file.hpp), written by generators and `inspect`.

#include "core/shape.hpp"

#include <nlohmann/json_fwd.hpp>

namespace ccd::datasets {

/// Writes a shape's keys as a scene file names them into `object`: "shape", then "radius" or "half_extents"
/// (what generators write and `inspect` shows).
void put_shape_keys(nlohmann::json& object, const Shape& shape);

}  // namespace ccd::datasets
