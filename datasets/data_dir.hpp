#pragma once
/// @file
/// Where the public data with exact ground truth lives (docs/DESIGN.md §7).

#include <filesystem>
#include <optional>

namespace ccd::datasets {

/// CCDBENCH_DATA_DIR when set; else `data/external` of the checkout (where scripts/fetch-data.sh puts it) when it
/// exists; else nullopt. (The scripts may set CCDBENCH_DATA_DIR from other places first: scripts/data-dir.sh.)
std::optional<std::filesystem::path> external_data_dir();

}  // namespace ccd::datasets
