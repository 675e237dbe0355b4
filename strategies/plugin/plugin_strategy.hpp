#pragma once
/// @file
/// The strategy registry's doors for code outside ccdbench (strategies/registry.hpp):
/// - `plugin:PATH[:key=value]`: a plugin's whole step (ccdbench_plugin.h, `step`), its state kept across steps;
/// - `answers:DIR`: a folder of answer files, one per step (answer_files.hpp), for code that cannot be loaded.
/// Every contact they report is checked (contact_check.hpp); what fails is a fault of the step, counted apart and
/// written out to reproduce, never an answer.

#include "strategies/strategy_entry.hpp"

#include <string>

namespace ccd::plugin {

/// The entry of `name` ("plugin:PATH"). @throws std::invalid_argument when the library cannot be loaded, or has no
/// step function (a per-query plugin is a narrow phase: full+plugin:PATH).
strategies::StrategyEntry whole_step_entry(const std::string& name);

/// The entry of `name` ("answers:DIR"). @throws std::invalid_argument when DIR is not a folder.
strategies::StrategyEntry answers_entry(const std::string& name);

}  // namespace ccd::plugin
