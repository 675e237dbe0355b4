#include "datasets/sample_step.hpp"

#include "core/error.hpp"
#include "datasets/frame_source.hpp"
#include "datasets/input_file.hpp"

#include <nlohmann/json.hpp>

namespace ccd::datasets {
namespace {

void expect_same_count(const std::filesystem::path& candidates, std::size_t candidate_count, const QueryFile& queries) {
  if (candidate_count != queries.queries.size()) {
    throw InputError(candidates, {},
                     "has " + std::to_string(candidate_count) + " pairs but " + queries.path.string() + " has " +
                         std::to_string(queries.queries.size()) + " queries");
  }
}

}  // namespace

std::vector<std::pair<std::uint32_t, std::uint32_t>> read_candidate_pairs(const std::filesystem::path& path) {
  const nlohmann::json document = read_json_file(path, "candidate file");
  if (!document.is_array()) throw InputError(path, {}, "must be a JSON array of [id_a, id_b] pairs");
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  pairs.reserve(document.size());
  for (std::size_t i = 0; i < document.size(); ++i) {
    const auto& pair = document[i];
    if (!pair.is_array() || pair.size() != 2 || !pair[0].is_number_unsigned() || !pair[1].is_number_unsigned()) {
      throw InputError(path, "entry " + std::to_string(i), "must be a pair of non-negative integer ids");
    }
    pairs.emplace_back(pair[0].get<std::uint32_t>(), pair[1].get<std::uint32_t>());
  }
  return pairs;
}

bool is_sample_step_directory(const std::filesystem::path& directory) {
  return std::filesystem::is_directory(directory / "frames") && std::filesystem::is_directory(directory / "queries");
}

SampleStep load_sample_step(const std::filesystem::path& directory) {
  SampleStep step;
  step.directory = directory;
  const std::vector<std::filesystem::path> frames = expand_frame_files(directory / "frames");
  if (frames.size() < 2) throw InputError(directory / "frames", {}, "a step needs two consecutive frames");
  step.frame0_file = frames[0];
  step.frame1_file = frames[1];
  step.step = frames[0].stem().string();

  auto source = make_file_frame_source({frames[0], frames[1]});
  step.x0 = source->frame(0);
  step.x1 = source->frame(1);
  step.topology = MeshTopology(source->num_vertices(), source->faces());

  const auto vertex_count = static_cast<std::uint64_t>(step.topology.num_vertices());
  const auto edge_count = static_cast<std::uint64_t>(step.topology.num_edges());
  const auto face_count = static_cast<std::uint64_t>(step.topology.num_faces());

  step.vertex_face_queries = read_query_file(directory / "queries" / (step.step + "vf.csv"), QueryKind::vertex_face);
  step.edge_edge_queries = read_query_file(directory / "queries" / (step.step + "ee.csv"), QueryKind::edge_edge);

  const std::filesystem::path vf_path = directory / "boxes" / (step.step + "vf.json");
  for (const auto& [a, b] : read_candidate_pairs(vf_path)) {
    // Ids number vertices first, then edges, then faces (face = id - V - E).
    if (a >= vertex_count || b < vertex_count + edge_count || b >= vertex_count + edge_count + face_count) {
      throw InputError(vf_path, {},
                       "pair [" + std::to_string(a) + ", " + std::to_string(b) + "] is not (vertex id, face id) for " + std::to_string(vertex_count) +
                           " vertices, " + std::to_string(edge_count) + " edges, " + std::to_string(face_count) + " faces");
    }
    step.vertex_face_candidates.emplace_back(a, static_cast<FaceId>(b - vertex_count - edge_count));
  }
  expect_same_count(vf_path, step.vertex_face_candidates.size(), step.vertex_face_queries);

  const std::filesystem::path ee_path = directory / "boxes" / (step.step + "ee.json");
  for (const auto& [a, b] : read_candidate_pairs(ee_path)) {
    if (a < vertex_count || b < vertex_count || a >= vertex_count + edge_count || b >= vertex_count + edge_count) {
      throw InputError(ee_path, {}, "pair [" + std::to_string(a) + ", " + std::to_string(b) + "] is not two edge ids");
    }
    step.edge_edge_candidates.emplace_back(static_cast<std::uint32_t>(a - vertex_count), static_cast<std::uint32_t>(b - vertex_count));
  }
  expect_same_count(ee_path, step.edge_edge_candidates.size(), step.edge_edge_queries);
  return step;
}

}  // namespace ccd::datasets
