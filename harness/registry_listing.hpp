#pragma once
/// @file
/// `ccdbench strategies`: what the registries hold (strategies/registry.hpp, strategies/narrowphase_registry.hpp),
/// for people and for scripts.

#include <nlohmann/json.hpp>

#include <iosfwd>
#include <string>
#include <vector>

namespace ccd::harness {

/// {"strategies": [...], "narrow_phases": [...]}: each entry's name, help, keys (name, kind, allowed values,
/// default, help) and backends; a strategy's narrow phase, judging, baseline and availability; a narrow phase's
/// promise (conservative) and the keys its sweep varies. Each of `plugins` (paths) is listed too: as a strategy
/// (plugin:PATH) where it answers whole steps, as a narrow phase where it answers queries.
/// @throws std::invalid_argument when a plugin cannot be loaded.
nlohmann::json registry_listing(const std::vector<std::string>& plugins = {});

/// Prints the listing as tables (`json`: as one JSON object). Exit status 0.
int run_strategies(bool json, std::ostream& out, const std::vector<std::string>& plugins = {});

}  // namespace ccd::harness
