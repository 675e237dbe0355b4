#include "datasets/data_dir.hpp"

#include "ccd/config.hpp"

#include <cstdlib>

namespace ccd::datasets {

std::optional<std::filesystem::path> external_data_dir() {
  if (const char* value = std::getenv("CCDBENCH_DATA_DIR"); value != nullptr && *value != '\0') {
    return std::filesystem::path(value);
  }
  const std::filesystem::path fetched = std::filesystem::path(CCDBENCH_SOURCE_DIR) / "data" / "external";
  if (std::filesystem::is_directory(fetched)) return fetched;
  return std::nullopt;
}

}  // namespace ccd::datasets
