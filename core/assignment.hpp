#pragma once
/// @file
/// Primitive assignment (docs/DESIGN.md §1, the paper's six-bit masks): every used vertex and every edge is owned by
/// exactly one incident triangle, so that testing, for each candidate triangle pair (A, B), the primitives A owns
/// against B and those B owns against A generates every elementary pair exactly once.

#include "core/topology.hpp"

#include <cstdint>
#include <vector>

namespace ccd {

/// Bits 0..2: corner k of the face is owned by it; bits 3..5: edge k (corner k to corner k+1) is owned by it.
using AssignmentMask = std::uint8_t;

constexpr AssignmentMask owns_vertex_bit(int corner) { return static_cast<AssignmentMask>(1u << corner); }
constexpr AssignmentMask owns_edge_bit(int edge) { return static_cast<AssignmentMask>(1u << (3 + edge)); }

/// One mask per face. The owner of a vertex or an edge is its incident face of lowest id: a rule that needs no
/// state, gives the same masks on every run and thread count, and is independent of who asks.
std::vector<AssignmentMask> assign_primitives(const MeshTopology& topology);

}  // namespace ccd
