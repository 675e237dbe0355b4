#pragma once
/// @file
/// A plugin with per-query functions (ccdbench_plugin.h) as a narrow phase of the registry: `plugin:PATH[:key=value]`
/// wherever a narrow phase is named (`queries --method`, `stress --method`, `run --strategy full+plugin:PATH`).
/// Every answer is checked before it counts: an error, an undecided answer, a TOI that is not a number in [0, 1], or
/// an outcome the ABI does not define is a fault (NarrowPhaseResult::fault), counted apart and counted for the
/// verdicts as the `errors` key says.

#include "strategies/narrowphase/entry.hpp"
#include "strategies/plugin/ccdbench_plugin.h"

#include <string>

namespace ccd::plugin {

/// The registry's entry for `name` ("plugin:PATH"): the plugin's keys, then ccdbench's own (library.hpp).
/// @throws std::invalid_argument when the library cannot be loaded, or has no per-query functions.
narrowphase::NarrowPhaseEntry narrow_phase_entry(const std::string& name);

/// A plugin's answer checked and read as a narrow phase's result. `answer.message` need not be terminated.
narrowphase::NarrowPhaseResult checked_answer(const ccdbench_answer& answer, bool reports_toi, bool errors_count_as_hits);

/// Whether `name` is `plugin:...` (the head of a plugin spec).
bool names_plugin(const std::string& name);

}  // namespace ccd::plugin
