#pragma once
/// @file
/// Writing result files for scripts: whole or not at all.

#include <nlohmann/json_fwd.hpp>

#include <filesystem>

namespace ccd::harness {

/// Writes `document` (pretty-printed) to `path` atomically: a temporary file renamed into place.
void write_json_file(const std::filesystem::path& path, const nlohmann::json& document);

}  // namespace ccd::harness
