#pragma once
/// @file
/// What a narrow phase is to the registry (registry.hpp): its entry. Each narrow phase's file defines its entries
/// (FILE_entries()) from this alone; the registry collects them.

#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/narrowphase/spec.hpp"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ccd::narrowphase {

/// One key a `queries --sweep` varies, the others left at their defaults, and the values it takes.
struct SweepAxis {
  std::string key;
  std::vector<std::string> values;
};

struct NarrowPhaseEntry {
  std::string name;
  /// One line: what it computes and what it guarantees.
  std::string help;
  std::vector<KeySpec> keys;
  /// Promises no false negatives on any input: judged as conservative (0 misses and no late TOI are gated).
  bool conservative = false;
  /// The keys `queries --sweep` varies (its accuracies), one at a time.
  std::vector<SweepAxis> sweeps;
  /// Makes an instance from its keys (`keys` says which the reader holds, already checked).
  std::function<std::unique_ptr<NarrowPhase>(const SpecReader&)> make;
  /// Code from outside ccdbench (a plugin, a method of the calling program), which making an instance loads or
  /// starts: the resolved name an instance made from `keys` would have, without making one. Empty for the built-ins,
  /// which are a few settings: resolve_narrow_phase makes one to ask.
  std::function<std::string(const SpecReader&)> resolve = {};
};

/// What a strategy needs to know of its narrow phase before anything is made (registry.hpp's resolved_name and
/// validate): its resolved name, whether it promises no misses, and whether the OpenCL backend runs it.
struct ResolvedNarrowPhase {
  std::string name;
  bool conservative = false;
  bool on_device = false;
};

/// The narrow phase of a strategy spec that names none (docs/DESIGN.md §3): the one that never misses.
inline constexpr const char* kDefaultNarrowPhase = "conservative";

}  // namespace ccd::narrowphase
