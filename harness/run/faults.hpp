#pragma once
/// @file
/// What a cell's steps could not answer (strategies::Fault: a plugin's error, undecided or refused answer, a crash or
/// a hang under isolation), written out so that each can be replayed alone.

#include "core/scene.hpp"
#include "strategies/strategy.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

namespace ccd::harness {

/// Writes under `directory` (when there are faults): FAULTS.txt (per step: how many, and each kept one's message and
/// what reproduces it), step_K/vertex-face/errors.csv and step_K/edge-edge/errors.csv (the pairs as query files,
/// unlabelled: `ccdbench queries FILE --allow-unlabelled --method ...` replays them), and step_K/frame_0.ply and
/// frame_1.ply for a fault of a whole step (`ccdbench run --frames ... --thickness δ` replays it). Atomic per file.
/// Returns {"errors": count over the steps, "errors_written": directory} ({"errors": 0} when none).
nlohmann::json record_faults(const Scene& scene, const std::vector<std::vector<Vec3>>& frames, const std::vector<strategies::StepResult>& results,
                             const std::filesystem::path& directory);

/// Writes each step's answers as DIRECTORY/step_0000.csv, ... in the format answers:DIR reads (one `vf,V,F,TOI` or
/// `ee,A0,A1,B0,B1,TOI` line per pair, TOI empty when none; docs/audit.md "Answer files"), atomically per file.
void write_step_answers(const std::vector<strategies::StepResult>& results, const std::filesystem::path& directory);

}  // namespace ccd::harness
