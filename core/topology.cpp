#include "core/topology.hpp"

#include "core/error.hpp"

#include <algorithm>
#include <limits>
#include <string>

namespace ccd {

std::optional<FaceListProblem> find_face_list_problem(std::size_t num_vertices, std::span<const Face> faces) {
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const Face& face = faces[f];
    for (int k = 0; k < 3; ++k) {
      if (face[k] >= num_vertices) {
        return FaceListProblem{static_cast<FaceId>(f), "vertex index " + std::to_string(face[k]) + " out of range (the mesh has " +
                                                           std::to_string(num_vertices) + " vertices)"};
      }
    }
    if (face[0] == face[1] || face[1] == face[2] || face[0] == face[2]) {
      return FaceListProblem{static_cast<FaceId>(f), "degenerate face (repeated vertex index: " + std::to_string(face[0]) + " " +
                                                         std::to_string(face[1]) + " " + std::to_string(face[2]) + ")"};
    }
  }
  return std::nullopt;
}

namespace {

/// Counting sort of (key, face) incidences into compressed lists; faces come out ascending per key
/// because incidences are generated in ascending face order.
void build_incidence(std::size_t num_keys, const std::vector<std::pair<std::uint32_t, FaceId>>& incidences, std::vector<std::uint32_t>& begin,
                     std::vector<FaceId>& ids) {
  begin.assign(num_keys + 1, 0);
  for (const auto& [key, face] : incidences) ++begin[key + 1];
  for (std::size_t k = 0; k < num_keys; ++k) begin[k + 1] += begin[k];
  ids.resize(incidences.size());
  std::vector<std::uint32_t> cursor(begin.begin(), begin.end() - 1);
  for (const auto& [key, face] : incidences) ids[cursor[key]++] = face;
}

}  // namespace

MeshTopology::MeshTopology(std::size_t num_vertices, std::vector<Face> faces) : num_vertices_(num_vertices), faces_(std::move(faces)) {
  if (num_vertices_ > std::numeric_limits<VertexId>::max() || faces_.size() > std::numeric_limits<FaceId>::max() / 3) {
    throw InputError({}, {}, "mesh too large for 32-bit ids");
  }
  if (auto problem = find_face_list_problem(num_vertices_, faces_)) {
    throw InputError({}, "face " + std::to_string(problem->face), problem->reason);
  }

  // Unique edges in lexicographic order: sort the 3F half-edges, then collapse equal ones.
  std::vector<std::pair<Edge, std::uint32_t>> half_edges;  // (edge, 3*face + k)
  half_edges.reserve(3 * faces_.size());
  for (FaceId f = 0; f < faces_.size(); ++f) {
    for (std::uint32_t k = 0; k < 3; ++k) {
      half_edges.emplace_back(make_edge(faces_[f][k], faces_[f][(k + 1) % 3]), 3 * f + k);
    }
  }
  std::sort(half_edges.begin(), half_edges.end());
  face_edges_.resize(faces_.size());
  std::vector<std::pair<std::uint32_t, FaceId>> edge_incidences;
  edge_incidences.reserve(half_edges.size());
  for (const auto& [edge, slot] : half_edges) {
    if (edges_.empty() || edges_.back() != edge) edges_.push_back(edge);
    const auto e = static_cast<EdgeId>(edges_.size() - 1);
    face_edges_[slot / 3][slot % 3] = e;
    edge_incidences.emplace_back(e, slot / 3);
  }
  // Half-edges of one edge are sorted by slot, hence by face: incidence lists come out ascending. A face that
  // used one edge twice would be degenerate, which was rejected above.
  build_incidence(edges_.size(), edge_incidences, edge_face_begin_, edge_face_ids_);

  std::vector<std::pair<std::uint32_t, FaceId>> vertex_incidences;
  vertex_incidences.reserve(3 * faces_.size());
  for (FaceId f = 0; f < faces_.size(); ++f) {
    for (VertexId v : faces_[f]) vertex_incidences.emplace_back(v, f);
  }
  build_incidence(num_vertices_, vertex_incidences, vertex_face_begin_, vertex_face_ids_);

  for (std::size_t v = 0; v < num_vertices_; ++v) {
    if (vertex_face_begin_[v] == vertex_face_begin_[v + 1]) ++num_unused_vertices_;
  }
}

std::span<const FaceId> MeshTopology::edge_faces(EdgeId e) const {
  return {edge_face_ids_.data() + edge_face_begin_[e], edge_face_begin_[e + 1] - edge_face_begin_[e]};
}

std::span<const FaceId> MeshTopology::vertex_faces(VertexId v) const {
  return {vertex_face_ids_.data() + vertex_face_begin_[v], vertex_face_begin_[v + 1] - vertex_face_begin_[v]};
}

std::optional<EdgeId> MeshTopology::find_edge(VertexId a, VertexId b) const {
  const Edge wanted = make_edge(a, b);
  const auto it = std::lower_bound(edges_.begin(), edges_.end(), wanted);
  if (it == edges_.end() || *it != wanted) return std::nullopt;
  return static_cast<EdgeId>(it - edges_.begin());
}

std::size_t MeshTopology::num_boundary_edges() const {
  std::size_t count = 0;
  for (EdgeId e = 0; e < edges_.size(); ++e) count += edge_faces(e).size() == 1 ? 1 : 0;
  return count;
}

bool MeshTopology::share_vertex(FaceId f, FaceId g) const {
  for (VertexId a : faces_[f]) {
    for (VertexId b : faces_[g]) {
      if (a == b) return true;
    }
  }
  return false;
}

bool MeshTopology::share_edge(FaceId f, FaceId g) const {
  for (EdgeId a : face_edges_[f]) {
    for (EdgeId b : face_edges_[g]) {
      if (a == b) return true;
    }
  }
  return false;
}

}  // namespace ccd
