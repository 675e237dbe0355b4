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

#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/narrowphase/spec.hpp"
#include "strategies/strategy.hpp"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ccd::strategies {

/// What a strategy's factory is given: its own keys (checked) and, when it takes one, its narrow phase.
struct StrategyRequest {
  const narrowphase::SpecReader& keys;
  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase;
};

struct StrategyEntry {
  std::string name;
  /// One line: what it does.
  std::string help;
  /// Its own keys (the backend's too where it has one); every other key of a spec is its narrow phase's.
  std::vector<narrowphase::KeySpec> keys;
  /// "cpu", and "opencl" where `backend=opencl` runs it on an OpenCL device.
  std::vector<std::string> backends{"cpu"};
  /// NAME+NARROW (default conservative); false: it uses elementary tests of its own and refuses a narrow phase.
  bool takes_narrow_phase = true;
  Judging judging = Judging::elementary_pairs;
  /// The strategy whose cell (same scene, same narrow phase, same invocation) its speed-up is measured against.
  std::string baseline = "full";
  /// With its own elementary tests: the cause of its "no" on a missed pair's rows (fcl_elementary.hpp); empty:
  /// a miss is explained by the audit, as culled (never tested) or tested (the narrow phase said no).
  std::function<std::string(const narrowphase::PairRows&, bool vertex_face)> explain_miss;
  /// With its own elementary tests: its answer to one query at δ = 0, scored by `queries --method NAME`.
  std::function<bool(const narrowphase::PairRows&, bool vertex_face)> elementary_test;
  /// Why this build cannot make it (a dependency was not found at configure time); empty when it can.
  std::string unavailable;
  std::function<std::unique_ptr<Strategy>(StrategyRequest)> make;
};

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

/// A spec's or resolved name's head, short, for progress lines and file names: "full+cubic64", "fcl", and a file
/// head by its file's name ("full+plugin:libmy_ccd.so", "answers:run-7").
std::string short_label(const std::string& spec);

/// The entry of a spec or of a resolved name. @throws std::invalid_argument for an unknown strategy.
const StrategyEntry& strategy_entry_of(const std::string& spec);

}  // namespace ccd::strategies
