#pragma once
/// @file
/// What both of apccd's backends (cpu/ with TBB, opencl/) decide alike, so that they test the same pairs: the
/// settings and their keys, the object frames (centroids summed in vertex order), the session's budgets and length,
/// the session's end, and history. Everything here runs on the host in one fixed order; a backend only supplies
/// the per-vertex and per-pair values it computes (dangling vertices, admissible and pending pairs).

#include "core/scene.hpp"
#include "core/step.hpp"
#include "strategies/narrowphase/spec.hpp"
#include "strategies/strategy.hpp"

#include <cstdint>
#include <map>
#include <string>
#include <unordered_map>
#include <vector>

namespace ccd::strategies {

/// How long history keeps a pair's orientation (docs/DESIGN.md §3).
enum class HistoryMode {
  off,
  /// Rebuilt every step from the pairs the back end tested: a pair the front end drops this step is forgotten.
  step,
  /// The paper's: a pair, once tested, keeps its last orientation for the rest of the simulation; a flip is looked
  /// for whenever it is tested again, however many steps later.
  persistent,
};

/// What apccd's front end does with the pending and object pairs before the back end (key `heuristic`).
enum class FrontEnd {
  /// Nothing: every pending and object pair goes to the back end.
  off,
  /// The box filter alone: candidate triangle pairs whose fresh swept boxes overlap this step.
  boxes,
  /// The box filter, then the distance heuristic (separation_filter.hpp): elementary pairs it proves apart never
  /// reach the narrow phase. The paper's front end.
  on,
};

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
  /// The front end. The distance heuristic spares the narrow phase the pairs it proves apart, at 75-77 ns a pair on
  /// the public cloth-funnel candidates (narrowphase_benchmark's separation-filter/*, one core of an AMD EPYC): it pays
  /// in front of the conservative test (225-230 ns on the same pairs), while cubic64 costs about as much as the
  /// heuristic itself (81-110 ns), so in front of it `boxes` (no heuristic) is the cheaper front end.
  FrontEnd front_end = FrontEnd::on;
  /// Off by default: with the default (conservative) narrow phase there is no missed crossing for history to
  /// catch, and on the drape scene it cost about 2 ms of a 5 ms step and added false alarms. It pays only with a
  /// narrow phase that misses (measured: cubic64's misses 68 -> 67 on spinning-ball, 337 -> 314 on funnel).
  HistoryMode history = HistoryMode::off;
  /// Pairs across objects from fresh world-frame trees every step (true) or from the session's trees (false).
  /// Measured on the default spinning-ball with advancement: 2.46 ms per step for session trees against 0.88 ms
  /// for full's whole traversal, because a turning ball outgrows every centroid-relative budget.
  bool fresh_object_pairs = true;
};

/// Why a step ended its session: each step's counters session_end_REASON are 1 for the rule that ended the
/// session there (0 for the others, and all 0 while it goes on), so a summary's mean times its steps counts the
/// sessions each rule ended (issue 37). The paper's rules (docs/DESIGN.md §3: a session of adaptive length nf, ended early
/// when too many vertices dangle): nf_max, nf_adapted and dangling. Ours: pending (the pending list's cost,
/// pending_max) and inflation_cap (inflation_max, which shortens nf when a session starts), each with its reason
/// at its setting in ApccdSettings.
enum class SessionEnd {
  none,
  /// The session ran nf_max frames.
  nf_max,
  /// It ran the nf frames it started with, nf below nf_max because an earlier session ended early (nf halves) and
  /// has not grown back (nf doubles after a session with few dangling vertices).
  nf_adapted,
  /// It ran the frames that inflation_max allowed when it started (fewer than nf).
  inflation_cap,
  /// More than dangling_max of the vertices dangled.
  dangling,
  /// The pending list outgrew pending_max times the admissible pairs.
  pending,
  /// skip=off: every step is a session of one frame.
  skip_off,
};
/// Every reason a session ends, in the counters' order.
inline constexpr SessionEnd kSessionEnds[] = {SessionEnd::nf_max,   SessionEnd::nf_adapted, SessionEnd::inflation_cap,
                                              SessionEnd::dangling, SessionEnd::pending,    SessionEnd::skip_off};
/// The counter of a reason: "session_end_nf_max", ...
std::string session_end_counter(SessionEnd end);
/// Appends the step's session_end_* counters (one per reason in kSessionEnds, 1 for `end`).
void add_session_end_counters(SessionEnd end, std::vector<std::pair<std::string, double>>& counters);

/// The keys apccd itself declares (its backend's and its narrow phase's are declared by them).
std::vector<narrowphase::KeySpec> apccd_keys();

/// The settings from apccd's keys. @throws std::invalid_argument for nf_min > nf_max.
ApccdSettings read_apccd_settings(const narrowphase::SpecReader& keys);

/// The resolved name: "apccd+NARROW:skip=on:..." with every key, numbers as format_spec_number prints them.
std::string apccd_name(const ApccdSettings& settings, const std::string& narrow_phase_name);

/// The session logic: object frames, budgets, session length and end.
class ApccdSession {
 public:
  void init(const ApccdSettings& settings, const Scene& scene, std::span<const Vec3> first_frame);
  /// Whether this step starts a session (every step with skip=off).
  bool starts() const { return frame_ == 0; }
  int nf() const { return nf_; }

  /// Each moving object's centroid at both ends of the step, summed in vertex order (static objects: zero). Self
  /// contact does not change when an object moves as a whole, so budgets and self traversal live in its frame.
  void update_centroids(const StepView& step);
  const std::vector<Vec3>& centroid0() const { return centroid0_; }
  const std::vector<Vec3>& centroid1() const { return centroid1_; }
  /// Positions relative to their object's centroid (x - centroid, one rounding per coordinate).
  void relative_positions(const StepView& step, std::vector<Vec3>& relative0, std::vector<Vec3>& relative1) const;
  /// How far the moving objects' vertices move in this step relative to their object's centroid, in mean edge
  /// lengths of frame 0 (the mean over those vertices): the motion a session's budgets must cover. Call after
  /// update_centroids.
  double relative_motion(const StepView& step) const;
  /// The translations object b's frame makes relative to a's during the step (object_pairs=session): centroids
  /// move linearly, as vertices do, so the range of cb - ca.
  Box3 pair_offset(ObjectId a, ObjectId b) const;

  /// A session's first frame: each vertex's budget for the frames left of the session, from its relative motion
  /// (local) and its object's mean (global), at least δ per frame; nf is first shortened by inflation_max.
  /// Static objects' vertices get 0.
  void start(std::span<const Vec3> relative0, std::span<const Vec3> relative1, std::vector<double>& budget);

  /// Ends the session after nf frames, or early when too many vertices dangle or the pending list costs more than
  /// it saves; adapts nf for the next one (nf = 1 is a refit and full traversal every frame). Returns why the
  /// session ended at this step (SessionEnd::none while it goes on).
  SessionEnd advance(std::size_t dangling_vertices, std::size_t admissible, std::size_t pending);

 private:
  void limit_session_by_inflation(const std::vector<double>& budget);

  ApccdSettings settings_;
  const Scene* scene_ = nullptr;
  /// Each object's mean edge length in frame 0 (the scale of inflation_max).
  std::vector<double> mean_edge_;
  std::vector<Vec3> centroid0_, centroid1_;
  int nf_ = 1;
  int frame_ = 0;
  /// What set this session's nf when it started: nf_max, nf_adapted or inflation_cap.
  SessionEnd planned_ = SessionEnd::nf_max;
  double worst_dangling_ = 0;
};

/// History: pairs in close proximity keep their relative orientation across steps. For the tested pairs, the side
/// of the face a vertex is on and how two edges cross; a pair whose orientation flipped (where that can be a
/// crossing) is reported unless the test already did.
class ProximityHistory {
 public:
  explicit ProximityHistory(HistoryMode mode = HistoryMode::step) : mode_(mode) {}
  /// Records the orientations of `tested` at the end of the step and adds the flipped pairs to `collisions`;
  /// returns how many it added. HistoryMode::step forgets the pairs not in `tested`; persistent keeps them.
  std::size_t apply(const MeshTopology& topology, std::span<const Vec3> x1, const TestedPairs& tested, CollisionSet& collisions);
  std::size_t pairs() const { return vertex_face_.size() + edge_edge_.size(); }
  /// Bytes of the tables: buckets plus one node per entry (key, value, next pointer, cached hash).
  std::size_t bytes() const;

 private:
  HistoryMode mode_;
  std::unordered_map<VertexFacePair, std::int8_t> vertex_face_;
  std::unordered_map<EdgeEdgePair, std::int8_t> edge_edge_;
};

}  // namespace ccd::strategies
