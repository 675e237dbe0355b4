#include "datasets/data_dir.hpp"

#include "ccd/config.hpp"

#include <cstdlib>

namespace ccd::datasets {

std::optional<std::filesystem::path> external_data_dir() {
  if (const char* value = std::getenv("CCDBENCH_DATA_DIR"); value != nullptr && *value != '\0') {
    return std::filesystem::path(value);
  }
  const std::filesystem::path checkout(CCDBENCH_SOURCE_DIR);
  for (const std::filesystem::path& candidate : {checkout.parent_path() / "shared" / "data", checkout / "data" / "external"}) {
    if (std::filesystem::is_directory(candidate)) return candidate;
  }
  return std::nullopt;
}

}  // namespace ccd::datasets
