#pragma once
/// @file
/// `apccd`: the adaptive pipeline with a skipping-frame session (Wong, NCS 2009, Algorithm 1) on the CPU with TBB.
///
/// A session lasts nf frames, nf adapted between nf_min and nf_max. Its first frame refits every non-static
/// hierarchy with boxes inflated by each vertex's movement budget for the session (local: its own speed; global:
/// its object's mean speed; times the frames left) and traverses fully: the candidates form the pending list.
/// The following frames skip refit and traversal: vertices that left their budget are dangling, their triangles'
/// leaf boxes are enlarged to hold their fresh swept boxes and only those triangles are traversed (partial
/// traversal). The front end admits the pending pairs whose fresh swept boxes overlap; the back end runs the
/// elementary tests on them. History keeps, for tested pairs in close proximity, the side of the face a vertex
/// is on and how two edges cross, and reports a pair whose orientation flipped unless the test already did.
///
/// Why it never loses a candidate: a pair that comes within δ has overlapping fresh (δ/2-widened) swept boxes;
/// every fresh box lies inside its triangle's box in the hierarchy (within budget by construction, enlarged when
/// dangling), so the pair was found by the session's full traversal or by a partial traversal, and the front end
/// admits it. With a conservative narrow phase it misses nothing.
///
/// Knobs (spec keys, all recorded in the resolved name): skip (on/off), nf_min, nf_max, local, global,
/// dangling_max (fraction of dangling vertices that ends a session), heuristic (front end on/off), history.

#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

#include <map>

namespace ccd::strategies {

struct ApccdSettings {
  bool skip = true;
  int nf_min = 2;
  int nf_max = 8;
  double local = 1.0;
  double global = 0.25;
  double dangling_max = 0.05;
  bool heuristic = true;
  bool history = true;
};

/// Reads the apccd keys from `parameters`, removing them (what remains is the narrow phase's).
/// @throws std::invalid_argument for a malformed or out-of-range value.
ApccdSettings take_apccd_settings(std::map<std::string, std::string>& parameters);

std::unique_ptr<Strategy> make_apccd(const ApccdSettings& settings, std::unique_ptr<narrowphase::NarrowPhase> narrow_phase);

}  // namespace ccd::strategies
