#include "harness/sample_comparison.hpp"

#include <nlohmann/json.hpp>

#include <map>
#include <optional>
#include <set>

namespace ccd::harness {
namespace {

using PositionKey = std::array<double, 6>;

PositionKey key_of(const Vec3& at0, const Vec3& at1) { return {at0.x(), at0.y(), at0.z(), at1.x(), at1.y(), at1.z()}; }

/// Mesh vertices by their (x0, x1) coordinates; a coordinate pair shared by two vertices maps to none, since
/// a query row could then name either.
class VertexByCoordinates {
 public:
  explicit VertexByCoordinates(const datasets::SampleStep& step) {
    for (VertexId v = 0; v < step.x0.size(); ++v) {
      auto [it, inserted] = vertices_.emplace(key_of(step.x0[v], step.x1[v]), v);
      if (!inserted) it->second = std::nullopt;
    }
  }
  std::optional<VertexId> find(const Vec3& at0, const Vec3& at1) const {
    const auto it = vertices_.find(key_of(at0, at1));
    return it == vertices_.end() ? std::nullopt : it->second;
  }

 private:
  std::map<PositionKey, std::optional<VertexId>> vertices_;
};

std::optional<EdgeEdgePair> edge_pair_of_query(const VertexByCoordinates& vertices, const datasets::Query& query) {
  const auto& r = query.rounded;
  const auto a0 = vertices.find(r[0], r[4]), a1 = vertices.find(r[1], r[5]);
  const auto b0 = vertices.find(r[2], r[6]), b1 = vertices.find(r[3], r[7]);
  if (!a0 || !a1 || !b0 || !b1) return std::nullopt;
  return make_edge_edge_pair(make_edge(*a0, *a1), make_edge(*b0, *b1));
}

}  // namespace

SampleComparison compare_with_sample(const datasets::SampleStep& step, const CollisionSet& truth) {
  SampleComparison comparison;
  std::set<VertexFacePair> vf_candidates;
  for (std::size_t i = 0; i < step.vertex_face_candidates.size(); ++i) {
    const VertexFacePair pair{step.vertex_face_candidates[i].first, step.vertex_face_candidates[i].second};
    vf_candidates.insert(pair);
    if (!step.vertex_face_queries.queries[i].truth.value_or(false)) continue;
    ++comparison.vertex_face_positives;
    if (truth.contains(pair)) {
      ++comparison.vertex_face_found;
    } else if (comparison.missing.size() < 20) {
      comparison.missing.push_back("VF query " + std::to_string(i) + ": vertex " + std::to_string(pair.v) + ", face " + std::to_string(pair.f));
    }
  }
  const VertexByCoordinates vertices(step);
  std::set<EdgeEdgePair> ee_candidates;
  for (std::size_t i = 0; i < step.edge_edge_queries.queries.size(); ++i) {
    const datasets::Query& query = step.edge_edge_queries.queries[i];
    const auto pair = edge_pair_of_query(vertices, query);
    if (pair) ee_candidates.insert(*pair);
    if (!query.truth.value_or(false)) continue;
    ++comparison.edge_edge_positives;
    if (pair && truth.contains(*pair)) {
      ++comparison.edge_edge_found;
    } else if (comparison.missing.size() < 20) {
      comparison.missing.push_back("EE query " + std::to_string(i) + " (line " + std::to_string(query.first_line) +
                                   (pair ? ")" : "): its coordinates match no unique mesh vertices"));
    }
  }
  for (const auto& contact : truth.vertex_face()) comparison.vertex_face_outside_candidates += vf_candidates.count(contact.pair) ? 0 : 1;
  for (const auto& contact : truth.edge_edge()) comparison.edge_edge_outside_candidates += ee_candidates.count(contact.pair) ? 0 : 1;
  return comparison;
}

nlohmann::json to_json(const SampleComparison& c) {
  return {{"vf_sample_positives", c.vertex_face_positives},
          {"vf_found", c.vertex_face_found},
          {"ee_sample_positives", c.edge_edge_positives},
          {"ee_found", c.edge_edge_found},
          {"vf_outside_sample_candidates", c.vertex_face_outside_candidates},
          {"ee_outside_sample_candidates", c.edge_edge_outside_candidates},
          {"missing", c.missing}};
}

}  // namespace ccd::harness
