#pragma once
/// @file
/// `ccdbench inspect`: what a scene, step, frame sequence, mesh, query, truth or cache file holds.

#include <nlohmann/json.hpp>

#include <filesystem>
#include <iosfwd>

namespace ccd::harness {

/// Describes `path` as a JSON object with "path", "type" (mesh, frames, scene, sample_step, queries,
/// query_directory, truth, candidates, frame_cache) and the counts of that type: vertices, faces, edges,
/// frames, steps, queries, positives, and "max_displacement" per step for sequences.
/// @throws InputError for unreadable or unrecognized input.
nlohmann::json inspect_path(const std::filesystem::path& path);

/// The same description as readable text.
void print_inspection(const nlohmann::json& description, std::ostream& out);

}  // namespace ccd::harness
