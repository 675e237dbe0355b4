#pragma once
/// @file
/// Elementary pair ids, stable and comparable across strategies and the reference.
///
/// Both kinds are named by the scene's global vertex and face ids only (never by a strategy's own edge
/// numbering), so two sets computed by different code compare directly.

#include "core/topology.hpp"

#include <compare>
#include <cstddef>
#include <functional>

namespace ccd {

/// Vertex v against face f (v is not a corner of f).
struct VertexFacePair {
  VertexId v;
  FaceId f;

  friend auto operator<=>(const VertexFacePair&, const VertexFacePair&) = default;
};

/// Edge a against edge b (no shared vertex), canonical: each edge has v0 < v1 and a < b.
struct EdgeEdgePair {
  Edge a;
  Edge b;

  friend auto operator<=>(const EdgeEdgePair&, const EdgeEdgePair&) = default;
};

/// Face f of a mesh object against shape object `shape` (an analytic obstacle, core/shape.hpp). The shape is named
/// by its object id, the face by its global id.
struct FaceShapePair {
  FaceId f;
  ObjectId shape;

  friend auto operator<=>(const FaceShapePair&, const FaceShapePair&) = default;
};

/// The canonical id of the pair of edges (p, q), in either order.
inline EdgeEdgePair make_edge_edge_pair(Edge p, Edge q) { return p < q ? EdgeEdgePair{p, q} : EdgeEdgePair{q, p}; }

}  // namespace ccd

template <>
struct std::hash<ccd::VertexFacePair> {
  std::size_t operator()(const ccd::VertexFacePair& p) const noexcept { return std::hash<std::uint64_t>{}((std::uint64_t{p.v} << 32) | p.f); }
};

template <>
struct std::hash<ccd::EdgeEdgePair> {
  std::size_t operator()(const ccd::EdgeEdgePair& p) const noexcept {
    const std::uint64_t a = (std::uint64_t{p.a.v0} << 32) | p.a.v1;
    const std::uint64_t b = (std::uint64_t{p.b.v0} << 32) | p.b.v1;
    return std::hash<std::uint64_t>{}(a * 0x9E3779B97F4A7C15ull ^ b);
  }
};
