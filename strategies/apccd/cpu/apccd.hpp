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

#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

#include <map>

namespace ccd::strategies {

struct ApccdSettings {
  bool skip = true;
  int nf_min = 1;
  int nf_max = 8;
  double local = 1.0;
  double global = 0.25;
  double dangling_max = 0.05;
  /// A session whose pending list outgrows `pending_max` times the pairs the front end admits is too costly: it
  /// ends, and nf halves.
  double pending_max = 4.0;
  /// A session is shortened so that a self-colliding object's mean budget stays within this fraction of its mean
  /// edge length (0: every frame is a session start).
  double inflation_max = 0.5;
  /// The front end: candidate triangle pairs whose fresh swept boxes overlap, then elementary pairs the distance
  /// heuristic (separation_filter.hpp) cannot prove apart.
  bool heuristic = true;
  /// Off by default: with the default (conservative) narrow phase there is no missed crossing for history to
  /// catch, and on the drape scene it cost about 2 ms of a 5 ms step and added false alarms. It pays only with a
  /// narrow phase that misses (measured: cubic64's misses 68 -> 67 on spinning-ball, 337 -> 314 on funnel).
  bool history = false;
  /// Pairs across objects from fresh world-frame trees every step (true) or from the session's trees (false).
  /// Measured on the default spinning-ball with advancement: 2.46 ms per step for session trees against 0.88 ms
  /// for full's whole traversal, because a turning ball outgrows every centroid-relative budget.
  bool fresh_object_pairs = true;
};

/// The keys apccd itself accepts (the rest of a spec's keys are its narrow phase's).
std::vector<std::string> apccd_parameter_names();

/// Reads the apccd keys from `parameters`, removing them (what remains is the narrow phase's).
/// @throws std::invalid_argument for a malformed or out-of-range value.
ApccdSettings take_apccd_settings(std::map<std::string, std::string>& parameters);

std::unique_ptr<Strategy> make_apccd(const ApccdSettings& settings, std::unique_ptr<narrowphase::NarrowPhase> narrow_phase);

}  // namespace ccd::strategies
