#include "strategies/apccd/session.hpp"

#include "strategies/narrowphase/narrow_phase.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ccd::strategies {
namespace {

const char* front_end_name(FrontEnd front_end) {
  switch (front_end) {
    case FrontEnd::off: return "off";
    case FrontEnd::boxes: return "boxes";
    case FrontEnd::on: return "on";
  }
  return "on";
}

const char* history_name(HistoryMode mode) {
  switch (mode) {
    case HistoryMode::off: return "off";
    case HistoryMode::step: return "on";
    case HistoryMode::persistent: return "persistent";
  }
  return "off";
}

// Ranges of apccd's keys. A session longer than 1000 frames is far past any scene's coherence (and nf stays an
// exact int); budgets are multiples of motion, 1e6 of them already cover any scene; dangling_max is a fraction of
// the vertices; pending_max a ratio of pair counts; inflation_max a multiple of the mean edge length (1e9: no cap).
constexpr narrowphase::SpecRange kSessionFrames{1, 1000};
constexpr narrowphase::SpecRange kMotionFactor{0, 1e6};
constexpr narrowphase::SpecRange kFraction{0, 1};
constexpr narrowphase::SpecRange kPendingRatio{1, 1e9};
constexpr narrowphase::SpecRange kInflationCap{0, 1e9};

/// Slack of history's plausibility test, relative to the face's squared area (VF) or the edges' squared cross
/// product (EE), so the same at every scale. History only adds reports to what the narrow phase found: a looser
/// slack can only add false alarms, a tighter one only drops history's extra reports; no miss depends on it.
constexpr double kCrossingSlack = 1e-6;

/// Whether a flip of orientation can be a crossing: the vertex projects into the face (VF), or the closest points
/// of the two edges' lines lie on both segments (EE), at the end of the step, within kCrossingSlack.
bool crossing_is_plausible(const MeshTopology& topology, std::span<const Vec3> x, const VertexFacePair& p) {
  const Face& f = topology.face(p.f);
  const Vec3 a = x[f[0]], b = x[f[1]], c = x[f[2]], q = x[p.v];
  const Vec3 n = (b - a).cross(c - a);
  const double area2 = n.squaredNorm();
  if (!(area2 > 0)) return false;
  return (b - a).cross(q - a).dot(n) >= -kCrossingSlack * area2 && (c - b).cross(q - b).dot(n) >= -kCrossingSlack * area2 &&
         (a - c).cross(q - c).dot(n) >= -kCrossingSlack * area2;
}
bool crossing_is_plausible(const MeshTopology&, std::span<const Vec3> x, const EdgeEdgePair& p) {
  const Vec3 ea = x[p.a.v1] - x[p.a.v0], eb = x[p.b.v1] - x[p.b.v0], r = x[p.b.v0] - x[p.a.v0];
  const Vec3 m = ea.cross(eb);
  const double m2 = m.squaredNorm();
  if (!(m2 > 0)) return false;
  const double s = r.cross(eb).dot(m), u = r.cross(ea).dot(m);
  return s >= -kCrossingSlack * m2 && s <= (1 + kCrossingSlack) * m2 && u >= -kCrossingSlack * m2 && u <= (1 + kCrossingSlack) * m2;
}

/// Orientation of an elementary pair at the end of the step: which side of the face plane the vertex is on, or
/// the sign of the edges' triple product (b0 - a0)·(ea × eb). 0 when exactly degenerate.
int orientation(const MeshTopology& topology, std::span<const Vec3> x, const VertexFacePair& p) {
  const Face& f = topology.face(p.f);
  const double s = (x[f[1]] - x[f[0]]).cross(x[f[2]] - x[f[0]]).dot(x[p.v] - x[f[0]]);
  return (s > 0) - (s < 0);
}
int orientation(const MeshTopology&, std::span<const Vec3> x, const EdgeEdgePair& p) {
  const double s = (x[p.b.v0] - x[p.a.v0]).dot((x[p.a.v1] - x[p.a.v0]).cross(x[p.b.v1] - x[p.b.v0]));
  return (s > 0) - (s < 0);
}

}  // namespace

std::vector<narrowphase::KeySpec> apccd_keys() {
  using narrowphase::KeySpec;
  const ApccdSettings defaults;
  return {KeySpec::on_off("skip", defaults.skip, "skipping-frame sessions (off: every step is a session start)"),
          KeySpec::integer("nf_min", defaults.nf_min, kSessionFrames, "shortest session, in frames"),
          KeySpec::integer("nf_max", defaults.nf_max, kSessionFrames, "longest session, in frames"),
          KeySpec::number("local", defaults.local, kMotionFactor, "inflation by a vertex's own speed, per frame left in the session"),
          KeySpec::number("global", defaults.global, kMotionFactor, "inflation by its object's mean speed, per frame left in the session"),
          KeySpec::number("dangling_max", defaults.dangling_max, kFraction, "fraction of dangling vertices that ends a session"),
          KeySpec::number("pending_max", defaults.pending_max, kPendingRatio, "pending pairs per admissible pair that ends a session"),
          KeySpec::number("inflation_max", defaults.inflation_max, kInflationCap,
                          "a session is shortened so the mean budget stays within this fraction of the mean edge length"),
          KeySpec::choice("heuristic", {"on", "boxes", "off"}, front_end_name(defaults.front_end),
                          "the front end: on (the box filter, then the distance heuristic: the paper's), boxes (the box filter alone: "
                          "cheaper in front of a narrow phase that costs what the heuristic costs, such as cubic64), off (neither)",
                          {{"true", "on"}, {"1", "on"}, {"false", "off"}, {"0", "off"}}),
          KeySpec::choice("history", {"off", "on", "persistent"}, history_name(defaults.history),
                          "orientation history: off, on (pairs tested last step), persistent (the paper's: every pair tested since the start)",
                          {{"step", "on"}, {"true", "on"}, {"1", "on"}, {"false", "off"}, {"0", "off"}}),
          KeySpec::choice("object_pairs", {"fresh", "session"}, defaults.fresh_object_pairs ? "fresh" : "session",
                          "pairs across objects from tight trees refitted every step (fresh) or from the session's inflated trees")};
}

ApccdSettings read_apccd_settings(const narrowphase::SpecReader& keys) {
  ApccdSettings settings;
  settings.skip = keys.choice("skip") == "on";
  const std::string front_end = keys.choice("heuristic");
  settings.front_end = front_end == "on" ? FrontEnd::on : front_end == "boxes" ? FrontEnd::boxes : FrontEnd::off;
  const std::string history = keys.choice("history");
  settings.history = history == "persistent" ? HistoryMode::persistent : history == "on" ? HistoryMode::step : HistoryMode::off;
  settings.fresh_object_pairs = keys.choice("object_pairs") == "fresh";
  settings.nf_min = static_cast<int>(keys.integer("nf_min"));
  settings.nf_max = static_cast<int>(keys.integer("nf_max"));
  settings.local = keys.number("local");
  settings.global = keys.number("global");
  settings.dangling_max = keys.number("dangling_max");
  settings.pending_max = keys.number("pending_max");
  settings.inflation_max = keys.number("inflation_max");
  if (settings.nf_min > settings.nf_max) throw std::invalid_argument("apccd: nf_min must not exceed nf_max");
  return settings;
}

std::string apccd_name(const ApccdSettings& settings, const std::string& narrow_phase_name) {
  using narrowphase::format_spec_number;
  return "apccd+" + narrow_phase_name + ":skip=" + (settings.skip ? "on" : "off") + ":nf_min=" + std::to_string(settings.nf_min) +
         ":nf_max=" + std::to_string(settings.nf_max) + ":local=" + format_spec_number(settings.local) +
         ":global=" + format_spec_number(settings.global) + ":dangling_max=" + format_spec_number(settings.dangling_max) +
         ":pending_max=" + format_spec_number(settings.pending_max) + ":inflation_max=" + format_spec_number(settings.inflation_max) +
         ":heuristic=" + front_end_name(settings.front_end) + ":object_pairs=" + (settings.fresh_object_pairs ? "fresh" : "session") +
         ":history=" + history_name(settings.history);
}

void ApccdSession::init(const ApccdSettings& settings, const Scene& scene, std::span<const Vec3> first_frame) {
  settings_ = settings;
  scene_ = &scene;
  mean_edge_.assign(scene.objects().size(), 0.0);
  std::vector<std::size_t> edges(scene.objects().size(), 0);
  for (EdgeId e = 0; e < scene.topology().num_edges(); ++e) {
    const Edge edge = scene.topology().edge(e);
    const ObjectId id = scene.object_of_vertex(edge.v0);
    mean_edge_[id] += (first_frame[edge.v1] - first_frame[edge.v0]).norm();
    ++edges[id];
  }
  for (ObjectId id = 0; id < mean_edge_.size(); ++id) mean_edge_[id] /= static_cast<double>(std::max<std::size_t>(edges[id], 1));
  frame_ = 0;
  worst_dangling_ = 0;
  nf_ = settings_.skip ? settings_.nf_max : 1;
}

void ApccdSession::update_centroids(const StepView& step) {
  const std::size_t objects = scene_->objects().size();
  centroid0_.assign(objects, Vec3::Zero());
  centroid1_.assign(objects, Vec3::Zero());
  for (ObjectId id = 0; id < objects; ++id) {
    const SceneObject& object = scene_->object(id);
    if (object.kind == ObjectKind::static_object || object.num_vertices == 0) continue;
    for (std::size_t i = 0; i < object.num_vertices; ++i) {
      centroid0_[id] += step.x0[object.first_vertex + i];
      centroid1_[id] += step.x1[object.first_vertex + i];
    }
    centroid0_[id] /= static_cast<double>(object.num_vertices);
    centroid1_[id] /= static_cast<double>(object.num_vertices);
  }
}

void ApccdSession::relative_positions(const StepView& step, std::vector<Vec3>& relative0, std::vector<Vec3>& relative1) const {
  relative0.resize(step.x0.size());
  relative1.resize(step.x1.size());
  for (ObjectId id = 0; id < scene_->objects().size(); ++id) {
    const SceneObject& object = scene_->object(id);
    tbb::parallel_for(std::size_t{0}, object.num_vertices, [&](std::size_t i) {
      const std::size_t v = object.first_vertex + i;
      relative0[v] = step.x0[v] - centroid0_[id];
      relative1[v] = step.x1[v] - centroid1_[id];
    });
  }
}

double ApccdSession::relative_motion(const StepView& step) const {
  double sum = 0;
  std::size_t vertices = 0;
  for (ObjectId id = 0; id < scene_->objects().size(); ++id) {
    const SceneObject& object = scene_->object(id);
    if (object.kind == ObjectKind::static_object || !(mean_edge_[id] > 0)) continue;
    for (std::size_t i = 0; i < object.num_vertices; ++i) {
      const std::size_t v = object.first_vertex + i;
      sum += ((step.x1[v] - centroid1_[id]) - (step.x0[v] - centroid0_[id])).norm() / mean_edge_[id];
    }
    vertices += object.num_vertices;
  }
  return vertices > 0 ? sum / static_cast<double>(vertices) : 0.0;
}

Box3 ApccdSession::pair_offset(ObjectId a, ObjectId b) const {
  Box3 ca(centroid0_[a]), cb(centroid0_[b]);
  ca.extend(centroid1_[a]);
  cb.extend(centroid1_[b]);
  return Box3(cb.min() - ca.max(), cb.max() - ca.min());
}

void ApccdSession::start(std::span<const Vec3> relative0, std::span<const Vec3> relative1, std::vector<double>& budget) {
  budget.assign(scene_->topology().num_vertices(), 0.0);
  // Each vertex's budget per frame first: its own relative motion (local) and its object's mean (global), at least
  // δ (at rest, motion-proportional budgets are near zero and any jitter would dangle). The session's length
  // follows from them, and then the budgets for the frames left.
  for (ObjectId id = 0; id < scene_->objects().size(); ++id) {
    const SceneObject& object = scene_->object(id);
    if (object.kind == ObjectKind::static_object) continue;
    double mean_motion = 0;
    for (std::size_t i = 0; i < object.num_vertices; ++i) {
      const std::size_t v = object.first_vertex + i;
      mean_motion += (relative1[v] - relative0[v]).norm();
    }
    mean_motion /= static_cast<double>(std::max<std::size_t>(object.num_vertices, 1));
    tbb::parallel_for(std::size_t{0}, object.num_vertices, [&](std::size_t i) {
      const std::size_t v = object.first_vertex + i;
      budget[v] = std::max(scene_->thickness(), settings_.local * (relative1[v] - relative0[v]).norm() + settings_.global * mean_motion);
    });
  }
  limit_session_by_inflation(budget);
  const double frames_left = static_cast<double>(nf_ - 1);
  for (ObjectId id = 0; id < scene_->objects().size(); ++id) {
    const SceneObject& object = scene_->object(id);
    if (object.kind == ObjectKind::static_object) continue;
    tbb::parallel_for(std::size_t{0}, object.num_vertices, [&](std::size_t i) { budget[object.first_vertex + i] *= frames_left; });
  }
}

/// Shortens this session so that no self-colliding object's mean budget exceeds `inflation_max` of its mean edge
/// length: beyond that, inflated leaves overlap their neighbours' neighbours and the session's traversal and
/// pending list cost more than a fresh traversal each frame (measured at resolution 100, where cloth moves more
/// than an edge per frame relative to itself: apccd ran at 0.65x full with unlimited sessions). Reads per-frame
/// budgets.
void ApccdSession::limit_session_by_inflation(const std::vector<double>& budget) {
  const int planned = nf_;
  int allowed = settings_.nf_max;
  for (ObjectId id = 0; id < scene_->objects().size(); ++id) {
    const SceneObject& object = scene_->object(id);
    if (object.kind == ObjectKind::static_object || !object.self_collision || object.num_vertices == 0) continue;
    double mean_budget = 0;
    for (std::size_t i = 0; i < object.num_vertices; ++i) mean_budget += budget[object.first_vertex + i];
    mean_budget /= static_cast<double>(object.num_vertices);
    // A still object (zero budget) allows any session length unless inflation_max is 0; frames is compared with
    // nf_max before the conversion, so that no huge quotient is converted to int.
    const double frames = mean_budget > 0               ? settings_.inflation_max * mean_edge_[id] / mean_budget
                          : settings_.inflation_max > 0 ? std::numeric_limits<double>::infinity()
                                                        : 0.0;
    if (frames < settings_.nf_max) allowed = std::min(allowed, 1 + static_cast<int>(frames));
  }
  nf_ = std::clamp(std::min(nf_, allowed), settings_.nf_min, settings_.nf_max);
  planned_ = allowed < planned ? SessionEnd::inflation_cap : nf_ == settings_.nf_max ? SessionEnd::nf_max : SessionEnd::nf_adapted;
}

SessionEnd ApccdSession::advance(std::size_t dangling_vertices, std::size_t admissible, std::size_t pending) {
  if (!settings_.skip) {
    frame_ = 0;
    return SessionEnd::skip_off;
  }
  const double fraction = static_cast<double>(dangling_vertices) / static_cast<double>(std::max<std::size_t>(1, scene_->topology().num_vertices()));
  worst_dangling_ = std::max(worst_dangling_, fraction);
  ++frame_;
  const bool too_costly = static_cast<double>(pending) > settings_.pending_max * static_cast<double>(std::max<std::size_t>(admissible, 1));
  if (fraction > settings_.dangling_max || too_costly) {
    nf_ = std::max(settings_.nf_min, nf_ / 2);
    frame_ = 0;
    worst_dangling_ = 0;
    return fraction > settings_.dangling_max ? SessionEnd::dangling : SessionEnd::pending;
  }
  if (frame_ >= nf_) {
    if (worst_dangling_ < settings_.dangling_max / 4) nf_ = std::min(settings_.nf_max, nf_ * 2);
    frame_ = 0;
    worst_dangling_ = 0;
    return planned_;
  }
  return SessionEnd::none;
}

std::string session_end_counter(SessionEnd end) {
  switch (end) {
    case SessionEnd::none: return "session_end_none";
    case SessionEnd::nf_max: return "session_end_nf_max";
    case SessionEnd::nf_adapted: return "session_end_nf_adapted";
    case SessionEnd::inflation_cap: return "session_end_inflation_cap";
    case SessionEnd::dangling: return "session_end_dangling";
    case SessionEnd::pending: return "session_end_pending";
    case SessionEnd::skip_off: return "session_end_skip_off";
  }
  return "session_end_unknown";
}

void add_session_end_counters(SessionEnd end, std::vector<std::pair<std::string, double>>& counters) {
  for (const SessionEnd reason : kSessionEnds) counters.emplace_back(session_end_counter(reason), reason == end ? 1.0 : 0.0);
}

std::size_t ProximityHistory::apply(const MeshTopology& topology, std::span<const Vec3> x1, const TestedPairs& tested, CollisionSet& collisions) {
  std::size_t catches = 0;
  auto track = [&](const auto& pairs, auto& table) {
    using Table = std::remove_reference_t<decltype(table)>;
    Table next;
    // step: the table becomes this step's tested pairs; persistent: they are updated in place and the rest kept.
    Table& updated = mode_ == HistoryMode::persistent ? table : next;
    if (mode_ != HistoryMode::persistent) next.reserve(pairs.size());
    for (const auto& pair : pairs) {
      const int now = orientation(topology, x1, pair);
      const auto it = table.find(pair);
      if (it != table.end() && now != 0 && it->second != 0 && now != it->second && !collisions.contains(pair) &&
          crossing_is_plausible(topology, x1, pair)) {
        collisions.add(pair);
        ++catches;
      }
      updated.insert_or_assign(pair, static_cast<std::int8_t>(now));
    }
    if (mode_ != HistoryMode::persistent) table.swap(next);
  };
  track(tested.vertex_face, vertex_face_);
  track(tested.edge_edge, edge_edge_);
  if (catches > 0) collisions.normalize();
  return catches;
}

std::size_t ProximityHistory::bytes() const {
  auto table_bytes = [](const auto& table) {
    using Entry = typename std::remove_reference_t<decltype(table)>::value_type;
    return table.bucket_count() * sizeof(void*) + table.size() * (sizeof(Entry) + 2 * sizeof(void*));
  };
  return table_bytes(vertex_face_) + table_bytes(edge_edge_);
}

}  // namespace ccd::strategies
