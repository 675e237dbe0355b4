#pragma once
/// @file
/// The Scalable-CCD sample step layout (docs/DATA.md): frames/<S>.ply and <S+1>.ply,
/// boxes/<S>{vf,ee}.json (candidate primitive pairs), queries/<S>{vf,ee}.csv and mma_bool/<S>{vf,ee}_mma_bool.json.

#include "core/topology.hpp"
#include "datasets/query_file.hpp"

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace ccd::datasets {

struct SampleStep {
  std::filesystem::path directory;
  /// The step's number S, as in its file names ("227").
  std::string step;
  std::filesystem::path frame0_file;
  std::filesystem::path frame1_file;
  MeshTopology topology;
  std::vector<Vec3> x0;
  std::vector<Vec3> x1;
  /// Candidate VF pairs (vertex id, face id), from the source's ids (vertices, then edges, then faces).
  std::vector<std::pair<VertexId, FaceId>> vertex_face_candidates;
  /// Candidate EE pairs in the source's own edge numbering (match them by query coordinates, not by id).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edge_edge_candidates;
  QueryFile vertex_face_queries;
  QueryFile edge_edge_queries;
};

/// A candidate file (boxes/*.json): a JSON array of [id_a, id_b] pairs of non-negative integers.
/// @throws InputError when malformed.
std::vector<std::pair<std::uint32_t, std::uint32_t>> read_candidate_pairs(const std::filesystem::path& path);

/// Whether `directory` has the layout (a frames/ and a queries/ folder).
bool is_sample_step_directory(const std::filesystem::path& directory);

/// Loads the step with the lowest frame number S of `directory` (frames S and S+1).
/// @throws InputError for a missing file, a topology change between the frames, candidate ids out of range,
///         or candidate and query counts that differ.
SampleStep load_sample_step(const std::filesystem::path& directory);

}  // namespace ccd::datasets
