#pragma once
/// @file
/// FCL (the Flexible Collision Library) as a peer would use it for deforming meshes (DESIGN.md §3).
///
/// Both strategies keep one `fcl::BVHModel` per scene object, built once from frame 0. Each step updates a model
/// with `beginUpdateModel` / `updateSubModel` / `endUpdateModel(refit, bottom-up)`, after which its leaves bound a
/// triangle's old and new corners. Static objects are updated once at init and never again. Traversal is FCL's own:
/// `fcl::detail::selfCollide` for an object with self-collision (a model against itself, each pair of distinct
/// leaves once; identical triangles are never paired) and `fcl::detail::collide` for a collidable pair of objects.
/// FCL's traversal is sequential, so these strategies use one thread whatever `--threads` says, except for the
/// project's own narrow phase in `fcl-bvh`.
///
/// - `fcl`: FCL's `MeshContinuousCollisionTraversalNode` and its 6 VF + 9 EE cubic tests per triangle pair, with the
///   contact limit raised so that every colliding triangle pair is reported. FCL answers with triangle pairs, so the
///   strategy is judged at the triangle-pair level (Strategy::judging). Pairs of triangles that share a vertex are
///   tested like any other: FCL's own tests reject the elementary pairs that share a vertex (their four points are
///   coplanar at every t, so every coefficient of the cubic is exactly zero), and the pairs that share none are what
///   a fold contact needs.
/// - `fcl-bvh`: FCL's hierarchy and traversal as the broad phase only; its candidate triangle pairs go through the
///   project's expansion and narrow phases, so culling and elementary tests are judged apart.
///
/// FCL has no thickness and its volumes are not inflated: both refuse δ > 0 (init throws).
/// Key: `bv` = aabb | obbrss | kdop24. The default is aabb, what a peer picks for a mesh refitted every step: its
/// refit is one min/max pass (OBBRSS fits oriented boxes again: 6.2 ms against 0.23 ms per step on the default
/// suite's spinning-ball), and its boxes hold touching contacts exactly. OBBRSS is not conservative at δ = 0: on the default
/// suite's pile, fcl-bvh:bv=obbrss culled one touching edge pair of two cloths lying flat (the fitted boxes are
/// flat too, and rounding separates them).

#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

#include <map>
#include <memory>
#include <string>

namespace ccd::strategies {

/// `fcl` from its parameters (only `bv`). @throws std::invalid_argument for an unknown key or bounding volume.
std::unique_ptr<Strategy> make_fcl(std::map<std::string, std::string> parameters);

/// `fcl-bvh+NARROW`: takes `bv` from `parameters`; the rest is the narrow phase's.
/// @throws std::invalid_argument for an unknown bounding volume.
std::unique_ptr<Strategy> make_fcl_bvh(std::map<std::string, std::string> parameters, const std::string& narrow_phase);

}  // namespace ccd::strategies
