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

/// A `--strategy` spec `NAME[+NARROW][:key=value...]` parsed once (parse_strategy_spec), what a run carries from the
/// command line to its cells: the entries it names and each key given to its owner. Nothing is made to parse it (a
/// plugin's table is described by a child process, never loaded here).
struct StrategySpec {
  /// As given: results name the cell by it (`spec`), and the gate and `compare` match cells by it.
  std::string text;
  const StrategyEntry* entry = nullptr;
  /// The narrow phase it runs (conservative unless named); null for a strategy with tests of its own.
  const narrowphase::NarrowPhaseEntry* narrow = nullptr;
  /// The strategy's own keys and its narrow phase's, as given.
  narrowphase::SpecParameters own, narrow_keys;
  /// Code or answers from outside ccdbench (a plugin, answer files, a method of the calling program): its errors
  /// and nondeterminism are verdicts, where a built-in's are defects.
  bool from_outside = false;
  /// The head, short, for progress lines and file names (short_label).
  std::string label;
};

/// Parses a spec: its strategy and narrow phase looked up, each key routed to its owner.
/// @throws std::invalid_argument for a malformed spec, an unknown strategy or narrow phase (naming the known ones), a
///         narrow phase given to a strategy that takes none, or a key neither owns (naming both lists).
StrategySpec parse_strategy_spec(const std::string& text);

/// Checks everything a strategy's factory would check before it builds anything: each key's value, that this build
/// has the strategy, and its entry's own check (a key of the other backend; backend=opencl: a narrow phase the device
/// runs, and the device). Makes nothing: no plugin is loaded, no device context made. @throws std::invalid_argument.
void validate(const StrategySpec& spec);

/// The name a strategy made from `spec` would have (Strategy::name(), every default filled in): what a run plans,
/// keys and keeps its cells by, without making the strategy. For a validated spec (its entry's check is not run again).
std::string resolved_name(const StrategySpec& spec);

/// Throws std::invalid_argument when the strategy cannot run `scene` (fcl at δ > 0), without making it.
void check_scene(const StrategySpec& spec, const Scene& scene);

/// Makes the strategy: only where a cell runs, and for its audit pass (docs/DESIGN.md §3).
/// @throws std::invalid_argument as validate does, or for what only making it can tell (a plugin's configuration).
std::unique_ptr<Strategy> make_strategy(const StrategySpec& spec);
/// Parses `text` and makes the strategy (tests, and tools outside a run).
std::unique_ptr<Strategy> make_strategy(const std::string& text);

/// The strategy's and the narrow phase's names in a spec or a resolved name.
struct StrategyNames {
  std::string name;
  std::string narrow_phase;
};
/// The names in a spec or a resolved name ("full+cubic64:eta=1e-06:...": full, cubic64; "fcl:bv=aabb": fcl and ""),
/// read from the head alone (a resolved name's device may hold any text), for records read back.
StrategyNames strategy_names_of(const std::string& spec);

/// Whether a spec or resolved name runs code or answers from outside ccdbench (a plugin, as the strategy or as its
/// narrow phase, or answer files): its errors and nondeterminism are verdicts, where a built-in's are defects.
bool from_outside(const std::string& spec);

/// Whether a spec runs a method of the calling program (callable:NAME, strategies/plugin/host_method.hpp): code
/// ccdbench cannot digest, so its cells are never kept for a later run.
bool runs_host_method(const std::string& spec);

/// Whether a spec or resolved name runs a plugin's code (plugin:PATH, as the strategy or as its narrow phase): code
/// whose answers can depend on what no digest covers (its environment, files it reads, libraries it opens itself or
/// that LD_PRELOAD puts before its own), so a cell of it is reused only when a run is asked to resume
/// (docs/DESIGN.md §10 "Kept cells").
bool runs_plugin(const std::string& spec);

/// A spec's or resolved name's head, short, for progress lines and file names: "full+cubic64", "fcl", and a file
/// head by its file's name ("full+plugin:libmy_ccd.so", "answers:run-7").
std::string short_label(const std::string& spec);

/// The entry of a spec or of a resolved name. @throws std::invalid_argument for an unknown strategy.
const StrategyEntry& strategy_entry_of(const std::string& spec);

}  // namespace ccd::strategies
