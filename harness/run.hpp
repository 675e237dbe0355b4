#pragma once
/// @file
/// `ccdbench run`: every strategy over every step of every scene, verified against exact truth, timed, recorded.

#include "datasets/scene_sequence.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace ccd::harness {

/// A scene to run, loaded only when its turn comes.
struct SceneSource {
  std::string label;
  std::function<datasets::SceneSequence()> load;
};

/// The scenes of a suite: `ci` (seconds), `default` (what scripts/run.sh runs: under two minutes on 2 cores, truth
/// included), `paper` (tens of thousands of triangles, a hundred frames).
/// @throws std::invalid_argument for an unknown suite.
std::vector<SceneSource> suite_scenes(const std::string& suite);
std::vector<std::string> suite_names();

struct RunOptions {
  std::vector<SceneSource> scenes;
  std::vector<std::string> strategies{"full"};
  std::optional<double> thickness;
  /// Verify every step against the exact truth.
  bool verify = true;
  /// Timed passes over the whole sequence; ms per step is the median over them.
  int repeats = 1;
  std::filesystem::path out = "results";
  std::optional<std::filesystem::path> json;
  std::optional<std::filesystem::path> report;
  bool fresh = false;
  /// Write every cell's missed pairs here as query files, by cause (`--misses`).
  std::optional<std::filesystem::path> misses;
  /// Only the first N steps of each scene (0: all).
  std::size_t max_steps = 0;
  std::string command_line;
};

/// Runs the cells, prints the table and writes the results. Returns the summaries (DESIGN.md §5 fields).
std::vector<nlohmann::json> run_benchmark(const RunOptions& options, std::ostream& out);

/// The CI gate: each summary of `results` (a JSON array) may miss at most its `baseline` entry's max_missed
/// (matched by scene and strategy; a result absent from the baseline may miss none). Prints every violation.
/// @return whether every result is within its baseline.
bool check_against_baseline(const nlohmann::json& baseline, const nlohmann::json& results, std::ostream& out);

}  // namespace ccd::harness
