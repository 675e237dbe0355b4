#pragma once
/// @file
/// What `ccdbench run` is asked to do (run.hpp runs it; run/cells.hpp runs one cell of it).

#include "datasets/scene_sequence.hpp"
#include "strategies/registry.hpp"

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace ccd::harness {

/// A scene to run, loaded only when its turn comes.
struct SceneSource {
  std::string label;
  std::function<datasets::SceneSequence()> load;
};

struct RunOptions {
  std::vector<SceneSource> scenes;
  /// Parsed once, where the run is asked for (the command line, the C++ API): every cell carries its spec.
  std::vector<strategies::StrategySpec> strategies;
  /// The thicknesses every scene runs at: nullopt is the scene's own δ; empty means {nullopt}. With more than one, a
  /// strategy that refuses a scene at one of them (fcl at δ > 0) is left out there, and said so, not an error.
  std::vector<std::optional<double>> thicknesses;
  /// Verify every step against the exact truth.
  bool verify = true;
  /// Also compare every reported TOI with the exact earliest contact (docs/DESIGN.md §5; needs verify): toi_late
  /// (reported later than exact, a defect for conservative methods), toi_error_max and toi_error_mean.
  bool toi = false;
  /// Timed passes over the whole sequence; ms per step is the median over them.
  int repeats = 1;
  /// The timed passes of a scene's cells at one δ run in turn, pass 1 of each cell, then pass 2 (`--interleave`):
  /// a machine that slows down during the run slows every cell's passes alike, and compare tests two such cells
  /// pass by pass (docs/ci-regression.md, "Time verdicts").
  bool interleave = false;
  std::filesystem::path out = "results";
  std::optional<std::filesystem::path> json;
  std::optional<std::filesystem::path> report;
  bool fresh = false;
  /// Also reuse kept cells of plugins (`--resume`): a plugin's answers can depend on what no digest covers, so
  /// without it a plugin's cell is computed again (docs/DESIGN.md §10 "Kept cells"), and a reused one is marked
  /// `resumed`, which `check` refuses unless told otherwise.
  bool resume = false;
  /// Write every cell's missed pairs here as query files, by cause (`--misses`).
  std::optional<std::filesystem::path> misses;
  /// Where what a step could not answer (a plugin's errors, crashes, hangs) is written to replay (`--faults`);
  /// default: OUT/faults.
  std::optional<std::filesystem::path> faults;
  /// Write every cell's answers here, one file per step (`--write-answers`), as answers:DIR reads them.
  std::optional<std::filesystem::path> write_answers;
  /// Only the first N steps of each scene (0: all).
  std::size_t max_steps = 0;
  std::string command_line;
};

}  // namespace ccd::harness
