#pragma once
/// @file
/// What a strategy is to the registry (registry.hpp): its entry. Each strategy's file defines its entries
/// (FILE_entries()) from this alone; the registry collects them.

#include "strategies/narrowphase/entry.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/narrowphase/spec.hpp"
#include "strategies/strategy.hpp"

#include <functional>
#include <memory>
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
  /// The name a strategy made from these keys would have (its Strategy::name()), without making one: what a run
  /// plans and keeps its cells by. `narrow` is its narrow phase's (unused by one with tests of its own).
  std::function<std::string(const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase& narrow)> resolve;
  /// What its factory would refuse in these keys and narrow phase beyond each key's own range (a key of the other
  /// backend, a narrow phase the device does not run, a device that is not there), said without making anything.
  std::function<void(const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase& narrow)> check = {};
  /// Throws std::invalid_argument when it cannot run `scene` (fcl at δ > 0), as its Strategy::check_scene does, before
  /// any work. Empty: it runs any scene.
  std::function<void(const narrowphase::SpecReader& keys, const Scene& scene)> check_scene = {};
};

}  // namespace ccd::strategies
