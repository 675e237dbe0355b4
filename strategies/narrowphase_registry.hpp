#pragma once
/// @file
/// The narrow-phase registry: the one door through which a narrow phase enters (docs/DESIGN.md §3). Each entry owns its
/// name, its keys (values, defaults, help), a one-line description, what it promises, the accuracy a `--sweep`
/// varies and its factory; strategies, `queries`, `stress`, the OpenCL backend and `ccdbench strategies` read it.
///
/// The list is the build's: strategies/narrowphase/CMakeLists.txt names one source file per line, and each file
/// FILE.cpp defines `std::vector<NarrowPhaseEntry> FILE_entries()`. A new narrow phase is its file and its line.

#include "strategies/narrowphase/entry.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/narrowphase/spec.hpp"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ccd::narrowphase {

/// Every narrow phase, in the order every listing shows them.
const std::vector<NarrowPhaseEntry>& narrow_phases();

/// The entry named `name`; `plugin:PATH` is the plugin's (strategies/plugin/plugin_narrow_phase.hpp), made at its
/// first lookup. @throws std::invalid_argument naming the known narrow phases, or why the plugin cannot be used.
const NarrowPhaseEntry& find_narrow_phase(const std::string& name);

/// Whether `name` names a narrow phase (any `plugin:PATH` does; whether it loads is find_narrow_phase's to say).
bool is_narrow_phase(const std::string& name);

/// Makes narrow phase `name` from its keys.
/// @throws std::invalid_argument for an unknown name or key, or a value it does not accept.
std::unique_ptr<NarrowPhase> make_narrow_phase(const std::string& name, const SpecParameters& parameters = {});

/// Parses `NAME[:key=value...]` and makes the variant.
std::unique_ptr<NarrowPhase> make_narrow_phase_from_spec(const std::string& spec);

/// What a strategy needs to know of narrow phase `entry` with these keys, without loading or starting any code.
ResolvedNarrowPhase resolve_narrow_phase(const NarrowPhaseEntry& entry, const SpecReader& keys);

/// The backends an entry runs on: "cpu", and "opencl" where its default instance has a device form.
std::vector<std::string> narrow_phase_backends(const NarrowPhaseEntry& entry);

/// The names of every narrow phase, comma-separated, for messages.
std::string narrow_phase_list();

}  // namespace ccd::narrowphase
