#pragma once
/// @file
/// Triangle mesh topology: unique edges, edge→faces, vertex→faces, adjacency tests.

#include "core/vec.hpp"

#include <array>
#include <optional>
#include <span>
#include <vector>

namespace ccd {

/// A triangle's corners, in the order the data gives them.
using Face = std::array<VertexId, 3>;

/// An undirected edge, stored with v0 < v1.
struct Edge {
  VertexId v0;
  VertexId v1;

  friend auto operator<=>(const Edge&, const Edge&) = default;
};

/// The edge between two distinct vertices, in canonical (v0 < v1) order.
inline Edge make_edge(VertexId a, VertexId b) { return a < b ? Edge{a, b} : Edge{b, a}; }

/// Whether two edges have an endpoint in common (such edge pairs are adjacent, never elementary pairs).
inline bool shares_vertex(const Edge& a, const Edge& b) { return a.v0 == b.v0 || a.v0 == b.v1 || a.v1 == b.v0 || a.v1 == b.v1; }

/// Why a face list is not a valid triangle mesh: the first bad face and the reason.
struct FaceListProblem {
  FaceId face;
  std::string reason;
};

/// First face with an index >= num_vertices or a repeated corner (a degenerate face); nullopt when all are valid.
std::optional<FaceListProblem> find_face_list_problem(std::size_t num_vertices, std::span<const Face> faces);

/// Immutable topology of a triangle mesh (or of several, concatenated: the scene's global mesh).
/// Edge ids number the unique edges in lexicographic (v0, v1) order, so they depend only on the face set,
/// never on face order or on who built the topology. Edge k of face f runs from corner k to corner (k+1) mod 3.
class MeshTopology {
 public:
  MeshTopology() = default;
  /// @throws InputError (no file; "face N") when a face index is out of range or a corner repeats.
  MeshTopology(std::size_t num_vertices, std::vector<Face> faces);

  std::size_t num_vertices() const { return num_vertices_; }
  std::size_t num_faces() const { return faces_.size(); }
  std::size_t num_edges() const { return edges_.size(); }

  const std::vector<Face>& faces() const { return faces_; }
  const Face& face(FaceId f) const { return faces_[f]; }
  const std::vector<Edge>& edges() const { return edges_; }
  const Edge& edge(EdgeId e) const { return edges_[e]; }

  /// Edge ids of face f; entry k is the edge from corner k to corner (k+1) mod 3.
  const std::array<EdgeId, 3>& face_edges(FaceId f) const { return face_edges_[f]; }
  /// Faces incident to edge e, ascending (1 on a boundary, 2 inside a manifold, more on a non-manifold edge).
  std::span<const FaceId> edge_faces(EdgeId e) const;
  /// Faces incident to vertex v, ascending (empty for a vertex no face uses).
  std::span<const FaceId> vertex_faces(VertexId v) const;
  /// Id of the edge (a, b), or nullopt when no face has it.
  std::optional<EdgeId> find_edge(VertexId a, VertexId b) const;

  /// Whether some face uses v. Unused vertices are not primitives (docs/DESIGN.md §1).
  bool is_used(VertexId v) const { return !vertex_faces(v).empty(); }
  std::size_t num_unused_vertices() const { return num_unused_vertices_; }
  std::size_t num_boundary_edges() const;

  /// Whether faces f and g (f != g) share at least one corner.
  bool share_vertex(FaceId f, FaceId g) const;
  /// Whether faces f and g (f != g) share an edge.
  bool share_edge(FaceId f, FaceId g) const;

 private:
  std::size_t num_vertices_ = 0;
  std::size_t num_unused_vertices_ = 0;
  std::vector<Face> faces_;
  std::vector<Edge> edges_;
  std::vector<std::array<EdgeId, 3>> face_edges_;
  // Compressed adjacency lists: the faces of edge e are edge_face_ids_[edge_face_begin_[e] .. edge_face_begin_[e+1]).
  std::vector<std::uint32_t> edge_face_begin_;
  std::vector<FaceId> edge_face_ids_;
  std::vector<std::uint32_t> vertex_face_begin_;
  std::vector<FaceId> vertex_face_ids_;
};

}  // namespace ccd
