#pragma once
/// @file
/// `apccd`: the adaptive pipeline with a skipping-frame session (Wong, NCS 2009, Algorithm 1) on the CPU with TBB.
///
/// Hierarchies live in each object's own frame (positions relative to its centroid): self contact does not change
/// when an object moves as a whole, so a falling or carried cloth needs no inflation for its translation.
/// A session lasts nf frames, nf adapted between nf_min and nf_max. Its first frame refits every non-static
/// hierarchy with boxes inflated by each vertex's movement budget for the session (local: its own relative
/// motion; global: its object's mean relative motion; times the frames left) and traverses every self-colliding
/// object fully: the candidates form the pending list. The following frames skip refit and self traversal:
/// vertices that left their budget are dangling, their triangles' leaf boxes are enlarged to hold their fresh
/// boxes and only those triangles are traversed (partial traversal). Pairs across objects come every step from
/// world-frame trees refitted tightly over the step (object_pairs=fresh, the default), or from the session's
/// trees, one swept by the range of the centroids' offset during the step (object_pairs=session). The front end
/// admits the candidates whose fresh swept boxes overlap, and its distance heuristic (separation_filter.hpp) drops
/// their elementary pairs that provably stay farther apart than δ; the back end runs the elementary tests on the
/// rest. History keeps, for tested pairs in close proximity, the side of the face a vertex is on and how two edges
/// cross, and reports a pair whose orientation flipped (where that can be a crossing) unless the test already did.
///
/// Why it never loses a candidate: a pair that comes within δ at time t has relative positions within δ (same
/// object) or world positions within δ (two objects, each its relative position plus its centroid at t); every
/// relative position of the step lies in its triangle's leaf box (within budget by construction, enlarged when
/// dangling) and every centroid in the step's centroid range (or, with fresh object pairs, every world position of
/// the step in its fresh leaf box). So the pair is found by the session's traversal, a partial traversal or the pair
/// traversal, and the front end admits it. With a conservative narrow phase it misses nothing.
///
/// Knobs (spec keys, all recorded in the resolved name): skip (on/off), nf_min, nf_max, local, global,
/// dangling_max (fraction of dangling vertices that ends a session), pending_max (pending pairs per admissible
/// pair that ends a session), inflation_max (mean budget per mean edge length that shortens a session), heuristic
/// (front end on/off), history, object_pairs (fresh/session).

#include "strategies/apccd/session.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

namespace ccd::strategies {

std::unique_ptr<Strategy> make_apccd(const ApccdSettings& settings, std::unique_ptr<narrowphase::NarrowPhase> narrow_phase);

}  // namespace ccd::strategies
