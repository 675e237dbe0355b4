#pragma once
/// @file
/// One cell of `ccdbench run`: a strategy over every step of a scene, timed, judged against the truth, recorded.

#include "core/collision_set.hpp"
#include "harness/run/options.hpp"
#include "harness/run/records.hpp"

#include <functional>
#include <string>
#include <vector>

namespace ccd::harness {

/// A scene as a rank holds it: its frames and, when verifying, the truth of each step it has loaded.
struct SceneData {
  std::string label;
  datasets::SceneSequence sequence;
  std::vector<std::vector<Vec3>> frames;
  std::vector<CollisionSet> truth;  // per step, when verifying
  std::vector<bool> has_truth;      // which steps' truth this rank holds
  std::size_t steps = 0;            // the steps run (--max-steps may cut the scene's)
  std::string thickness_from;       // "scene" or "command line"
};

/// Told after each timed step of a cell: its pass (0-based) and step, and the resolved strategy, so that a long
/// cell shows that it moves (outside the timed region).
using CellProgress = std::function<void(int pass, std::size_t step, const std::string& strategy)>;

/// Runs one cell: repeats timed passes, judges the first against the truth, audits only when something is missed.
/// Returns its summary and step records (docs/DESIGN.md §5 fields).
/// `planned_name`: the resolved name the cell was planned (and its key made) with; a strategy that runs under another
/// (code from outside ccdbench that changed during the run) ends the run instead of being kept under that key.
CellRecord run_cell(const SceneData& data, const strategies::StrategySpec& spec, const RunOptions& options, std::size_t steps,
                    const std::string& cell_name, const CellProgress& progress = {}, const std::string& planned_name = {});

/// A cell of a scene to run: its spec, its file's name, the resolved name it was planned with (as run_cell's).
struct CellToRun {
  const strategies::StrategySpec* spec;
  std::string cell_name, planned_name;
};

/// Runs several cells of one scene at one δ with their timed passes in turn: pass 1 of each cell, then pass 2 of each
/// (`run --interleave`). A machine that slows down meanwhile slows every cell's passes alike, so compare can test two
/// of them pass by pass. Each cell is then judged and recorded as run_cell does, and its summary holds `group`.
std::vector<CellRecord> run_cells_interleaved(const SceneData& data, const std::vector<CellToRun>& cells, const RunOptions& options,
                                              std::size_t steps, const CellProgress& progress, const std::string& group);

}  // namespace ccd::harness
