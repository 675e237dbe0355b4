#include "strategies/apccd/cpu/apccd.hpp"

#include "core/assignment.hpp"
#include "strategies/elementary_tests.hpp"
#include "strategies/object_hierarchies.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <limits>
#include <unordered_map>

namespace ccd::strategies {
namespace {

bool parse_switch(const std::string& key, const std::string& value) {
  if (value == "on" || value == "true" || value == "1") return true;
  if (value == "off" || value == "false" || value == "0") return false;
  throw std::invalid_argument("apccd: " + key + "=" + value + " must be on or off");
}

double parse_number(const std::string& key, const std::string& value, narrowphase::SpecRange range) {
  return narrowphase::parse_spec_number("apccd", key, value, range);
}

// Ranges of apccd's keys. A session longer than 1000 frames is far past any scene's coherence (and nf stays an
// exact int); budgets are multiples of motion, 1e6 of them already cover any scene; dangling_max is a fraction of
// the vertices; pending_max a ratio of pair counts; inflation_max a multiple of the mean edge length (1e9: no cap).
constexpr narrowphase::SpecRange kSessionFrames{1, 1000, true};
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
  return s >= -kCrossingSlack * m2 && s <= (1 + kCrossingSlack) * m2 && u >= -kCrossingSlack * m2 &&
         u <= (1 + kCrossingSlack) * m2;
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

class Apccd final : public Strategy {
 public:
  Apccd(const ApccdSettings& settings, std::unique_ptr<narrowphase::NarrowPhase> narrow_phase)
      : settings_(settings), narrow_phase_(std::move(narrow_phase)), nf_(settings.nf_max) {}

  std::string name() const override {
    std::ostringstream out;
    out << "apccd+" << narrow_phase_->name() << ":skip=" << (settings_.skip ? "on" : "off") << ":nf_min=" << settings_.nf_min
        << ":nf_max=" << settings_.nf_max << ":local=" << settings_.local << ":global=" << settings_.global
        << ":dangling_max=" << settings_.dangling_max << ":pending_max=" << settings_.pending_max
        << ":inflation_max=" << settings_.inflation_max
        << ":heuristic=" << (settings_.heuristic ? "on" : "off")
        << ":object_pairs=" << (settings_.fresh_object_pairs ? "fresh" : "session")
        << ":history=" << (settings_.history ? "on" : "off");
    return out.str();
  }

  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    scene_ = &scene;
    masks_ = assign_primitives(scene.topology());
    hierarchies_.build(scene, first_frame, scene.thickness() / 2);
    mean_edge_.assign(scene.objects().size(), 0.0);
    std::vector<std::size_t> edges(scene.objects().size(), 0);
    for (EdgeId e = 0; e < scene.topology().num_edges(); ++e) {
      const Edge edge = scene.topology().edge(e);
      const ObjectId id = scene.object_of_vertex(edge.v0);
      mean_edge_[id] += (first_frame[edge.v1] - first_frame[edge.v0]).norm();
      ++edges[id];
    }
    for (ObjectId id = 0; id < mean_edge_.size(); ++id) mean_edge_[id] /= static_cast<double>(std::max<std::size_t>(edges[id], 1));
    if (settings_.fresh_object_pairs && !scene.collidable_pairs().empty()) fresh_.build(scene, first_frame, scene.thickness() / 2);
    session_frame_ = 0;
    nf_ = settings_.skip ? settings_.nf_max : 1;
    pending_.clear();
    vertex_face_history_.clear();
    edge_edge_history_.clear();
  }

  StepResult step(const StepView& step, bool audit) override {
    StepResult result;
    const MeshTopology& topology = scene_->topology();
    const double half = scene_->thickness() / 2;
    std::size_t dangling_vertices = 0, dangling_triangles = 0;
    const bool session_start = session_frame_ == 0;
    {
      ScopedStageTimer timer(result.stages, "update");
      to_object_frames(step);
    }
    if (session_start) {
      start_session(result);
    } else {
      // Dangling vertices: beyond their budget around the session's anchor, in their object's frame, at either end
      // of the step. A vertex coming back within its budget still moves outside it during the step, on a segment
      // that its enlarged leaf holds but that no earlier partial traversal searched from.
      std::vector<FaceId> dangling_faces;
      {
        ScopedStageTimer timer(result.stages, "dangling collection");
        std::vector<char> dangling(topology.num_vertices(), 0);
        auto outside = [&](const Vec3& relative, std::size_t v) {
          return (relative - anchor_[v]).cwiseAbs().maxCoeff() > budget_[v];
        };
        tbb::parallel_for(std::size_t{0}, topology.num_vertices(), [&](std::size_t v) {
          dangling[v] = outside(relative0_[v], v) || outside(relative1_[v], v) ? 1 : 0;
        });
        std::vector<char> face_dangles(topology.num_faces(), 0);
        for (std::size_t v = 0; v < dangling.size(); ++v) {
          if (!dangling[v]) continue;
          ++dangling_vertices;
          for (FaceId f : topology.vertex_faces(static_cast<VertexId>(v))) face_dangles[f] = 1;
        }
        for (FaceId f = 0; f < topology.num_faces(); ++f) {
          if (face_dangles[f]) dangling_faces.push_back(f);
        }
        dangling_triangles = dangling_faces.size();
      }
      {
        ScopedStageTimer timer(result.stages, "partial traversal");
        partial_traversal(dangling_faces, half);
      }
    }
    std::vector<bvh::TrianglePair> across;
    {
      // Pairs across objects, every step: each tree holds its object's relative positions, so it is swept by the
      // range its object's centroid covers during this step (centroids move linearly, as vertices do).
      ScopedStageTimer timer(result.stages, "object pairs");
      if (!scene_->collidable_pairs().empty()) {
        if (settings_.fresh_object_pairs) {
          // The session's budgets bound motion relative to an object's centroid, which a turning object (the
          // spinning ball) exceeds everywhere: its inflated tree then overlaps far too much. A refit of tight
          // world-frame trees and their traversal, as `full` does, costs less there.
          fresh_.refit(step, half);
          across = fresh_.pair_candidates([](ObjectId, ObjectId) { return Box3(Vec3::Zero(), Vec3::Zero()); });
        } else {
          across = hierarchies_.pair_candidates([&](ObjectId a, ObjectId b) {
            const Box3 ca = centroid_range(a), cb = centroid_range(b);
            return Box3(cb.min() - ca.max(), cb.max() - ca.min());
          });
        }
      }
    }
    std::vector<bvh::TrianglePair> admissible;
    {
      ScopedStageTimer timer(result.stages, "front end");
      if (settings_.heuristic) {
        // Admissible: the two triangles' fresh swept boxes, widened by δ/2, overlap this step. Each face's box is
        // computed once per step; candidate pairs then only compare two boxes.
        std::vector<Box3> face_boxes(topology.num_faces());
        tbb::parallel_for(std::size_t{0}, topology.num_faces(), [&](std::size_t f) {
          face_boxes[f] = bvh::swept_face_box(topology.face(static_cast<FaceId>(f)), step.x0, step.x1, half);
        });
        // The pending list and this step's object pairs are filtered in place of a merged copy: the back end's
        // answer does not depend on the order of its candidates.
        for (const auto* list : {&pending_, &across}) {
          std::vector<char> keep(list->size(), 0);
          tbb::parallel_for(std::size_t{0}, list->size(), [&](std::size_t i) {
            keep[i] = face_boxes[(*list)[i].first].intersects(face_boxes[(*list)[i].second]) ? 1 : 0;
          });
          for (std::size_t i = 0; i < list->size(); ++i) {
            if (keep[i]) admissible.push_back((*list)[i]);
          }
        }
      } else {
        admissible = pending_;
        admissible.insert(admissible.end(), across.begin(), across.end());
      }
    }
    ElementaryOutcome outcome;
    std::size_t history_catches = 0;
    {
      ScopedStageTimer timer(result.stages, "back end");
      // The front end's distance heuristic at the elementary level: pairs provably farther apart than δ over the
      // step never reach the narrow phase (separation_filter.hpp).
      outcome = test_candidates(topology, masks_, admissible, step, *narrow_phase_, scene_->thickness(),
                                audit || settings_.history, settings_.heuristic);
      if (settings_.history) history_catches = apply_history(step, *outcome.tested, outcome.collisions);
    }
    result.collisions = std::move(outcome.collisions);
    if (audit) result.tested = std::move(outcome.tested);
    result.counters.candidate_triangle_pairs = admissible.size();
    result.counters.elementary_tests = outcome.tests;
    result.counters.history_bytes =
        history_bytes() + pending_.capacity() * sizeof(bvh::TrianglePair) + hierarchies_.bytes() + fresh_.bytes();
    result.counters.extra = {{"session_start", session_start ? 1.0 : 0.0},
                             {"nf", static_cast<double>(nf_)},
                             {"pending_pairs", static_cast<double>(pending_.size())},
                             {"dangling_vertices", static_cast<double>(dangling_vertices)},
                             {"dangling_triangles", static_cast<double>(dangling_triangles)},
                             {"history_pairs", static_cast<double>(vertex_face_history_.size() + edge_edge_history_.size())},
                             {"history_catches", static_cast<double>(history_catches)},
                             {"history_table_bytes", static_cast<double>(history_bytes())},
                             {"distance_filtered", static_cast<double>(outcome.filtered)}};
    advance_session(dangling_vertices, admissible.size());
    return result;
  }

 private:
  /// Each object's frame: positions relative to its centroid (static objects stay in world coordinates). Self
  /// contact does not change when an object moves as a whole, so budgets and self traversal live in this frame.
  void to_object_frames(const StepView& step) {
    const std::size_t objects = scene_->objects().size();
    centroid0_.assign(objects, Vec3::Zero());
    centroid1_.assign(objects, Vec3::Zero());
    relative0_.resize(step.x0.size());
    relative1_.resize(step.x1.size());
    for (ObjectId id = 0; id < objects; ++id) {
      const SceneObject& object = scene_->object(id);
      if (object.kind != ObjectKind::static_object && object.num_vertices > 0) {
        for (std::size_t i = 0; i < object.num_vertices; ++i) {
          centroid0_[id] += step.x0[object.first_vertex + i];
          centroid1_[id] += step.x1[object.first_vertex + i];
        }
        centroid0_[id] /= static_cast<double>(object.num_vertices);
        centroid1_[id] /= static_cast<double>(object.num_vertices);
      }
      tbb::parallel_for(std::size_t{0}, object.num_vertices, [&](std::size_t i) {
        const std::size_t v = object.first_vertex + i;
        relative0_[v] = step.x0[v] - centroid0_[id];
        relative1_[v] = step.x1[v] - centroid1_[id];
      });
    }
  }

  Box3 centroid_range(ObjectId object) const {
    Box3 range(centroid0_[object]);
    range.extend(centroid1_[object]);
    return range;
  }

  /// First frame of a session: budgets, inflated refit, full self traversal into the pending list.
  void start_session(StepResult& result) {
    const MeshTopology& topology = scene_->topology();
    const double half = scene_->thickness() / 2;
    {
      ScopedStageTimer timer(result.stages, "update");
      anchor_ = relative1_;
      budget_.assign(topology.num_vertices(), 0.0);
      // Each vertex's budget per frame first: its own relative motion (local) and its object's mean (global), at
      // least δ (at rest, motion-proportional budgets are near zero and any jitter would dangle). The session's
      // length follows from them, and then the budgets for the frames left.
      for (ObjectId id = 0; id < scene_->objects().size(); ++id) {
        const SceneObject& object = scene_->object(id);
        if (object.kind == ObjectKind::static_object) continue;
        double mean_motion = 0;
        for (std::size_t i = 0; i < object.num_vertices; ++i) {
          const std::size_t v = object.first_vertex + i;
          mean_motion += (relative1_[v] - relative0_[v]).norm();
        }
        mean_motion /= static_cast<double>(std::max<std::size_t>(object.num_vertices, 1));
        tbb::parallel_for(std::size_t{0}, object.num_vertices, [&](std::size_t i) {
          const std::size_t v = object.first_vertex + i;
          budget_[v] = std::max(scene_->thickness(), settings_.local * (relative1_[v] - relative0_[v]).norm() + settings_.global * mean_motion);
        });
      }
      limit_session_by_inflation();
      const double frames_left = static_cast<double>(nf_ - 1);
      for (ObjectId id = 0; id < scene_->objects().size(); ++id) {
        const SceneObject& object = scene_->object(id);
        if (object.kind == ObjectKind::static_object) continue;
        tbb::parallel_for(std::size_t{0}, object.num_vertices, [&](std::size_t i) { budget_[object.first_vertex + i] *= frames_left; });
        std::vector<double> inflation(object.num_faces);
        tbb::parallel_for(std::size_t{0}, object.num_faces, [&](std::size_t i) {
          const Face& face = topology.face(static_cast<FaceId>(object.first_face + i));
          inflation[i] = half + std::max({budget_[face[0]], budget_[face[1]], budget_[face[2]]});
        });
        hierarchies_.refit(id, relative0_, relative1_, inflation);
      }
    }
    {
      ScopedStageTimer timer(result.stages, "traversal");
      pending_ = hierarchies_.self_candidates();
    }
  }

  /// Shortens this session so that no self-colliding object's mean budget exceeds `inflation_max` of its mean
  /// edge length: beyond that, inflated leaves overlap their neighbours' neighbours and the session's traversal and
  /// pending list cost more than a fresh traversal each frame (measured at resolution 100, where cloth moves more
  /// than an edge per frame relative to itself: apccd ran at 0.65x full with unlimited sessions).
  /// Reads the per-frame budgets in budget_.
  void limit_session_by_inflation() {
    int allowed = settings_.nf_max;
    for (ObjectId id = 0; id < scene_->objects().size(); ++id) {
      const SceneObject& object = scene_->object(id);
      if (object.kind == ObjectKind::static_object || !object.self_collision || object.num_vertices == 0) continue;
      double mean_budget = 0;
      for (std::size_t i = 0; i < object.num_vertices; ++i) mean_budget += budget_[object.first_vertex + i];
      mean_budget /= static_cast<double>(object.num_vertices);
      // A still object (zero budget) allows any session length unless inflation_max is 0; frames is compared
      // with nf_max before the conversion, so that no huge quotient is converted to int.
      const double frames = mean_budget > 0 ? settings_.inflation_max * mean_edge_[id] / mean_budget
                            : settings_.inflation_max > 0 ? std::numeric_limits<double>::infinity()
                                                          : 0.0;
      if (frames < settings_.nf_max) allowed = std::min(allowed, 1 + static_cast<int>(frames));
    }
    nf_ = std::clamp(std::min(nf_, allowed), settings_.nf_min, settings_.nf_max);
  }

  /// Enlarges the dangling triangles' leaves to their fresh boxes, then finds every face whose box overlaps one of
  /// them, within what the collision filter allows; new pairs join the pending list.
  void partial_traversal(const std::vector<FaceId>& dangling_faces, double half) {
    if (dangling_faces.empty()) return;
    const MeshTopology& topology = scene_->topology();
    std::vector<Box3> fresh(dangling_faces.size());
    tbb::parallel_for(std::size_t{0}, dangling_faces.size(), [&](std::size_t i) {
      fresh[i] = bvh::swept_face_box(topology.face(dangling_faces[i]), relative0_, relative1_, half);
    });
    // Enlarged leaves keep every tree valid; object pairs then see them through the per-step pair traversal.
    for (std::size_t i = 0; i < dangling_faces.size(); ++i) hierarchies_.enlarge_leaf(dangling_faces[i], fresh[i]);
    std::vector<bvh::TrianglePair> found;
    std::size_t begin = 0;
    while (begin < dangling_faces.size()) {
      // dangling_faces is sorted, so each object's faces form one run.
      const ObjectId object = scene_->object_of_face(dangling_faces[begin]);
      std::size_t end = begin;
      while (end < dangling_faces.size() && scene_->object_of_face(dangling_faces[end]) == object) ++end;
      if (scene_->object(object).self_collision) {
        const auto pairs = bvh::subset_overlaps(std::span(dangling_faces).subspan(begin, end - begin),
                                                std::span<const Box3>(fresh).subspan(begin, end - begin),
                                                hierarchies_.tree(object));
        found.insert(found.end(), pairs.begin(), pairs.end());
      }
      begin = end;
    }
    if (found.empty()) return;
    // The pending list is a sorted vector rather than a hash table: merging sorted runs keeps it duplicate-free,
    // deterministic and compact, and the front end reads it sequentially.
    tbb::parallel_sort(found.begin(), found.end());
    std::vector<bvh::TrianglePair> merged;
    merged.reserve(pending_.size() + found.size());
    std::set_union(pending_.begin(), pending_.end(), found.begin(), found.end(), std::back_inserter(merged));
    pending_.swap(merged);
  }

  /// Reports tested pairs in close proximity whose orientation flipped since they were last seen, when the
  /// elementary test did not; returns how many it added.
  std::size_t apply_history(const StepView& step, const TestedPairs& tested, CollisionSet& collisions) {
    const MeshTopology& topology = scene_->topology();
    std::size_t catches = 0;
    auto track = [&](const auto& pairs, auto& table) {
      using Table = std::remove_reference_t<decltype(table)>;
      Table next;
      next.reserve(pairs.size());
      for (const auto& pair : pairs) {
        const int now = orientation(topology, step.x1, pair);
        const auto it = table.find(pair);
        if (it != table.end() && now != 0 && it->second != 0 && now != it->second && !collisions.contains(pair) &&
            crossing_is_plausible(topology, step.x1, pair)) {
          collisions.add(pair);
          ++catches;
        }
        next.emplace(pair, static_cast<std::int8_t>(now));
      }
      table.swap(next);
    };
    track(tested.vertex_face, vertex_face_history_);
    track(tested.edge_edge, edge_edge_history_);
    if (catches > 0) collisions.normalize();
    return catches;
  }

  /// Bytes of the history tables: buckets plus one node per entry (key, value, next pointer, cached hash).
  std::size_t history_bytes() const {
    auto table_bytes = [](const auto& table) {
      using Entry = typename std::remove_reference_t<decltype(table)>::value_type;
      return table.bucket_count() * sizeof(void*) + table.size() * (sizeof(Entry) + 2 * sizeof(void*));
    };
    return table_bytes(vertex_face_history_) + table_bytes(edge_edge_history_);
  }

  /// Ends the session after nf frames, or early when too many vertices dangle or the pending list costs more than
  /// it saves; adapts nf for the next one (nf = 1 is a refit and full traversal every frame).
  void advance_session(std::size_t dangling_vertices, std::size_t admissible) {
    if (!settings_.skip) {
      session_frame_ = 0;
      return;
    }
    const double fraction = static_cast<double>(dangling_vertices) / static_cast<double>(std::max<std::size_t>(1, scene_->topology().num_vertices()));
    worst_dangling_ = std::max(worst_dangling_, fraction);
    ++session_frame_;
    const bool too_costly = static_cast<double>(pending_.size()) > settings_.pending_max * static_cast<double>(std::max<std::size_t>(admissible, 1));
    if (fraction > settings_.dangling_max || too_costly) {
      nf_ = std::max(settings_.nf_min, nf_ / 2);
      session_frame_ = 0;
      worst_dangling_ = 0;
    } else if (session_frame_ >= nf_) {
      if (worst_dangling_ < settings_.dangling_max / 4) nf_ = std::min(settings_.nf_max, nf_ * 2);
      session_frame_ = 0;
      worst_dangling_ = 0;
    }
  }

  ApccdSettings settings_;
  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase_;
  const Scene* scene_ = nullptr;
  std::vector<AssignmentMask> masks_;
  ObjectHierarchies hierarchies_;
  /// World-frame trees refitted every step for the pairs across objects (fresh_object_pairs).
  ObjectHierarchies fresh_;
  int nf_;
  int session_frame_ = 0;
  double worst_dangling_ = 0;
  /// Positions in each object's frame at the step's ends, and the centroids that define those frames.
  std::vector<Vec3> relative0_, relative1_;
  std::vector<Vec3> centroid0_, centroid1_;
  std::vector<Vec3> anchor_;
  std::vector<double> budget_;
  /// Each object's mean edge length in frame 0 (the scale of inflation_max).
  std::vector<double> mean_edge_;
  std::vector<bvh::TrianglePair> pending_;
  std::unordered_map<VertexFacePair, std::int8_t> vertex_face_history_;
  std::unordered_map<EdgeEdgePair, std::int8_t> edge_edge_history_;
};

}  // namespace

std::vector<std::string> apccd_parameter_names() {
  return {"skip", "nf_min", "nf_max", "local", "global", "dangling_max", "pending_max", "inflation_max", "heuristic",
          "history", "object_pairs"};
}

ApccdSettings take_apccd_settings(std::map<std::string, std::string>& parameters) {
  ApccdSettings settings;
  auto take = [&](const char* key, auto apply) {
    const auto it = parameters.find(key);
    if (it == parameters.end()) return;
    apply(it->second);
    parameters.erase(it);
  };
  take("skip", [&](const std::string& v) { settings.skip = parse_switch("skip", v); });
  take("heuristic", [&](const std::string& v) { settings.heuristic = parse_switch("heuristic", v); });
  take("history", [&](const std::string& v) { settings.history = parse_switch("history", v); });
  take("object_pairs", [&](const std::string& v) {
    if (v != "fresh" && v != "session") throw std::invalid_argument("apccd: object_pairs=" + v + " must be fresh or session");
    settings.fresh_object_pairs = v == "fresh";
  });
  take("nf_min", [&](const std::string& v) { settings.nf_min = static_cast<int>(parse_number("nf_min", v, kSessionFrames)); });
  take("nf_max", [&](const std::string& v) { settings.nf_max = static_cast<int>(parse_number("nf_max", v, kSessionFrames)); });
  take("local", [&](const std::string& v) { settings.local = parse_number("local", v, kMotionFactor); });
  take("global", [&](const std::string& v) { settings.global = parse_number("global", v, kMotionFactor); });
  take("dangling_max", [&](const std::string& v) { settings.dangling_max = parse_number("dangling_max", v, kFraction); });
  take("pending_max", [&](const std::string& v) { settings.pending_max = parse_number("pending_max", v, kPendingRatio); });
  take("inflation_max", [&](const std::string& v) { settings.inflation_max = parse_number("inflation_max", v, kInflationCap); });
  if (settings.nf_min > settings.nf_max) throw std::invalid_argument("apccd: nf_min must not exceed nf_max");
  return settings;
}

std::unique_ptr<Strategy> make_apccd(const ApccdSettings& settings, std::unique_ptr<narrowphase::NarrowPhase> narrow_phase) {
  return std::make_unique<Apccd>(settings, std::move(narrow_phase));
}

}  // namespace ccd::strategies
