#pragma once
/// @file
/// The strategy registry: the one door through which a strategy enters (docs/DESIGN.md §3). Each entry owns its name,
/// its keys (values, defaults, help), a one-line description, the backends it runs on, whether it takes a narrow
/// phase, what its answers are judged by, the strategy its speed-up is measured against, how a miss of it is
/// explained, and its factory. `run`, `queries`, `ccdbench strategies`, MPI work items and cell keys read it; the
/// harness never dispatches on a strategy's spelling.
///
/// The list is the build's: strategies/CMakeLists.txt names one source file per line, and each file FILE.cpp
/// defines `std::vector<StrategyEntry> FILE_entries()`.

#include "strategies/narrowphase/spec.hpp"
#include "strategies/strategy_entry.hpp"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ccd::strategies {

/// Every strategy, in the order every listing shows them.
const std::vector<StrategyEntry>& strategy_entries();

/// The entry named `name`. @throws std::invalid_argument naming the known strategies.
const StrategyEntry& find_strategy(const std::string& name);

/// A spec `NAME[+NARROW][:key=value...]`, split. `narrow_phase` is empty when the spec names none.
struct StrategySpec {
  std::string name;
  std::string narrow_phase;
  narrowphase::SpecParameters parameters;
};
/// @throws std::invalid_argument for a malformed spec.
StrategySpec parse_strategy_spec(const std::string& spec);

/// Makes a strategy from its spec (`full`, `full+cubic64`, `apccd:skip=off`, ...): its keys to it, the rest to its
/// narrow phase (conservative unless named).
/// @throws std::invalid_argument naming the known strategies, or the unknown key with both lists of keys, or a value
///         out of range, or a backend or dependency this build lacks.
std::unique_ptr<Strategy> make_strategy(const std::string& spec);

/// The strategy's and the narrow phase's names in a spec or a resolved name ("full+cubic64:eta=1e-06:...": full,
/// cubic64; "fcl:bv=aabb": fcl and ""), read from the head alone (a resolved name's device may hold any text).
StrategySpec strategy_names_of(const std::string& spec);

/// Whether a spec or resolved name runs code or answers from outside ccdbench (a plugin, as the strategy or as its
/// narrow phase, or answer files): its errors and nondeterminism are verdicts, where a built-in's are defects.
bool from_outside(const std::string& spec);

/// Whether a spec runs a method of the calling program (callable:NAME, strategies/plugin/host_method.hpp): code
/// ccdbench cannot digest, so its cells are never kept for a later run.
bool runs_host_method(const std::string& spec);

/// A spec's or resolved name's head, short, for progress lines and file names: "full+cubic64", "fcl", and a file
/// head by its file's name ("full+plugin:libmy_ccd.so", "answers:run-7").
std::string short_label(const std::string& spec);

/// The entry of a spec or of a resolved name. @throws std::invalid_argument for an unknown strategy.
const StrategyEntry& strategy_entry_of(const std::string& spec);

}  // namespace ccd::strategies
