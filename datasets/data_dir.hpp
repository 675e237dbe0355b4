#pragma once
/// @file
/// Where the public data with exact ground truth lives (DESIGN.md §7).

#include <filesystem>
#include <optional>

namespace ccd::datasets {

/// CCDBENCH_DATA_DIR when set; else `../shared/data` beside the checkout when it exists; else `data/external`
/// of the checkout (where scripts/fetch-data.sh puts it) when it exists; else nullopt.
std::optional<std::filesystem::path> external_data_dir();

}  // namespace ccd::datasets
