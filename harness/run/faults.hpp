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

/// Writes under `directory` (when there are faults): FAULTS.txt (per step: how many, each kept one's message and the
/// command that replays it, `spec` the cell's strategy as given), step_K/vertex-face/errors.csv and
/// step_K/edge-edge/errors.csv (the pairs as query files, labelled by the reference at the scene's δ, which they say),
/// and step_K/frame_0.ply and frame_1.ply for a fault of a whole step (`ccdbench run --frames ...` replays it). Steps
/// are numbered from 0, as everywhere. Atomic per file.
/// Returns {"errors": count over the steps, "errors_written": directory} ({"errors": 0} when none).
nlohmann::json record_faults(const Scene& scene, const std::vector<std::vector<Vec3>>& frames, const std::vector<strategies::StepResult>& results,
                             const std::filesystem::path& directory, const std::string& spec);

/// Writes each step's answers as DIRECTORY/step_0000.csv, ... in the format answers:DIR reads (one `vf,V,F,TOI` or
/// `ee,A0,A1,B0,B1,TOI` line per pair, TOI empty when none; docs/audit.md "Answer files"), atomically per file.
void write_step_answers(const std::vector<strategies::StepResult>& results, const std::filesystem::path& directory);

}  // namespace ccd::harness
