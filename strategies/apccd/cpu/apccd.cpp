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
/// (the front end: on, boxes, off), history, object_pairs (fresh/session).

#include "core/assignment.hpp"
#include "strategies/apccd/opencl/apccd_opencl.hpp"
#include "strategies/apccd/session.hpp"
#include "strategies/backend.hpp"
#include "strategies/elementary_tests.hpp"
#include "strategies/face_shape.hpp"
#include "strategies/object_hierarchies.hpp"
#include "strategies/opencl/full_opencl.hpp"
#include "strategies/strategy_entry.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

namespace ccd::strategies {
namespace {

/// Appends the pairs of `list` for which keep(pair) holds to `out`, in their order: in parallel, each chunk of the list
/// into a list of its own, the chunks' lists then concatenated in order (the same result for any thread count). One
/// core copying the kept pairs one by one took about as long as the box tests on both (front end, 319k pending pairs).
template <class Keep>
void append_kept(std::span<const bvh::TrianglePair> list, const Keep& keep, std::vector<bvh::TrianglePair>& out) {
  constexpr std::size_t kChunk = 8192;
  const std::size_t chunks = (list.size() + kChunk - 1) / kChunk;
  std::vector<std::vector<bvh::TrianglePair>> kept(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
    const std::size_t end = std::min(list.size(), (c + 1) * kChunk);
    for (std::size_t i = c * kChunk; i < end; ++i) {
      if (keep(list[i])) kept[c].push_back(list[i]);
    }
  });
  std::vector<std::size_t> offsets(chunks + 1, out.size());
  for (std::size_t c = 0; c < chunks; ++c) offsets[c + 1] = offsets[c] + kept[c].size();
  out.resize(offsets[chunks]);
  tbb::parallel_for(std::size_t{0}, chunks,
                    [&](std::size_t c) { std::copy(kept[c].begin(), kept[c].end(), out.begin() + static_cast<std::ptrdiff_t>(offsets[c])); });
}

class Apccd final : public Strategy {
 public:
  Apccd(const ApccdSettings& settings, std::unique_ptr<narrowphase::NarrowPhase> narrow_phase)
      : settings_(settings), narrow_phase_(std::move(narrow_phase)) {}

  std::string name() const override { return apccd_name(settings_, narrow_phase_->name()); }

  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    scene_ = &scene;
    masks_ = assign_primitives(scene.topology());
    hierarchies_.build(scene, first_frame, scene.thickness() / 2);
    session_.init(settings_, scene, first_frame);
    if (settings_.fresh_object_pairs && !scene.collidable_pairs().empty()) fresh_.build(scene, first_frame, scene.thickness() / 2);
    pending_.clear();
    found_.clear();
    history_ = ProximityHistory(settings_.history);
  }

  StepResult step(const StepView& step, bool audit) override {
    StepResult result;
    const MeshTopology& topology = scene_->topology();
    const double half = scene_->thickness() / 2;
    std::size_t dangling_vertices = 0, dangling_triangles = 0;
    const bool session_start = session_.starts();
    double relative_motion = 0;
    {
      ScopedStageTimer timer(result.stages, "update");
      session_.update_centroids(step);
      session_.relative_positions(step, relative0_, relative1_);
      relative_motion = session_.relative_motion(step);
    }
    if (session_start) {
      start_session(result);
    } else {
      const std::vector<FaceId> dangling_faces = collect_dangling(result, dangling_vertices);
      dangling_triangles = dangling_faces.size();
      {
        ScopedStageTimer timer(result.stages, "partial traversal");
        partial_traversal(dangling_faces, half);
      }
    }
    const std::vector<bvh::TrianglePair> across = object_pairs(step, half, result);
    const std::vector<bvh::TrianglePair> admissible = admissible_pairs(step, half, across, result);
    ElementaryOutcome outcome;
    std::size_t history_catches = 0;
    // The front end's distance heuristic at the elementary level ("distance heuristic", timed on its own as on the
    // device): pairs provably farther apart than δ over the step never reach the narrow phase
    // (separation_filter.hpp). The back end: the narrow phase, then history.
    outcome = test_candidates(topology, masks_, admissible, step, *narrow_phase_, scene_->thickness(), audit || settings_.history != HistoryMode::off,
                              settings_.front_end == FrontEnd::on, result.stages, "back end");
    if (settings_.history != HistoryMode::off) {
      ScopedStageTimer timer(result.stages, "back end");
      history_catches = history_.apply(topology, step.x1, *outcome.tested, outcome.collisions);
    }
    result.collisions = std::move(outcome.collisions);
    if (audit) result.tested = std::move(outcome.tested);
    result.counters.candidate_triangle_pairs = admissible.size();
    result.counters.elementary_tests = outcome.tests;
    // Memory by part (the paper's 48 MB for 142k pending pairs): the pending list, the trees, history's tables.
    const std::size_t pending_pairs = pending_.size() + found_.size();
    const std::size_t pending_bytes = (pending_.capacity() + found_.capacity()) * sizeof(bvh::TrianglePair);
    const std::size_t tree_bytes = hierarchies_.bytes() + fresh_.bytes();
    result.counters.history_bytes = history_.bytes();
    result.counters.kept_bytes = history_.bytes() + pending_bytes + tree_bytes;
    result.counters.extra = {{"session_start", session_start ? 1.0 : 0.0},
                             {"nf", static_cast<double>(session_.nf())},
                             {"pending_pairs", static_cast<double>(pending_pairs)},
                             {"dangling_vertices", static_cast<double>(dangling_vertices)},
                             {"dangling_triangles", static_cast<double>(dangling_triangles)},
                             {"history_pairs", static_cast<double>(history_.pairs())},
                             {"history_catches", static_cast<double>(history_catches)},
                             {"history_table_bytes", static_cast<double>(history_.bytes())},
                             {"distance_filtered", static_cast<double>(outcome.filtered)},
                             {"admissible_pairs", static_cast<double>(admissible.size())},
                             {"object_pair_candidates", static_cast<double>(across.size())},
                             {"pending_bytes", static_cast<double>(pending_bytes)},
                             {"tree_bytes", static_cast<double>(tree_bytes)},
                             {"relative_motion", relative_motion}};
    // Shapes are beyond the paper: their faces are tested every step, as `full` does (face_shape.hpp).
    run_face_shape_stage(result, *scene_, step, *narrow_phase_, audit);
    add_session_end_counters(session_.advance(dangling_vertices, admissible.size(), pending_pairs), result.counters.extra);
    return result;
  }

 private:
  /// Dangling vertices: beyond their budget around the session's anchor, in their object's frame, at either end of
  /// the step (a vertex coming back within its budget still moves outside it during the step, on a segment that its
  /// enlarged leaf holds but that no earlier partial traversal searched from); returns their faces, counts them.
  std::vector<FaceId> collect_dangling(StepResult& result, std::size_t& dangling_vertices) {
    const MeshTopology& topology = scene_->topology();
    std::vector<FaceId> dangling_faces;
    ScopedStageTimer timer(result.stages, "dangling collection");
    std::vector<char> dangling(topology.num_vertices(), 0);
    auto outside = [&](const Vec3& relative, std::size_t v) { return (relative - anchor_[v]).cwiseAbs().maxCoeff() > budget_[v]; };
    tbb::parallel_for(std::size_t{0}, topology.num_vertices(),
                      [&](std::size_t v) { dangling[v] = outside(relative0_[v], v) || outside(relative1_[v], v) ? 1 : 0; });
    std::vector<char> face_dangles(topology.num_faces(), 0);
    for (std::size_t v = 0; v < dangling.size(); ++v) {
      if (!dangling[v]) continue;
      ++dangling_vertices;
      for (FaceId f : topology.vertex_faces(static_cast<VertexId>(v))) face_dangles[f] = 1;
    }
    for (FaceId f = 0; f < topology.num_faces(); ++f) {
      if (face_dangles[f]) dangling_faces.push_back(f);
    }
    return dangling_faces;
  }

  /// Pairs across objects, every step: each tree holds its object's relative positions, so it is swept by the range
  /// its object's centroid covers during this step (centroids move linearly, as vertices do).
  std::vector<bvh::TrianglePair> object_pairs(const StepView& step, double half, StepResult& result) {
    std::vector<bvh::TrianglePair> across;
    {
      ScopedStageTimer timer(result.stages, "object pairs");
      if (!scene_->collidable_pairs().empty()) {
        if (settings_.fresh_object_pairs) {
          // The session's budgets bound motion relative to an object's centroid, which a turning object (the
          // spinning ball) exceeds everywhere: its inflated tree then overlaps far too much. A refit of tight
          // world-frame trees and their traversal, as `full` does, costs less there.
          fresh_.refit(step, half);
          across = fresh_.pair_candidates([](ObjectId, ObjectId) { return Box3(Vec3::Zero(), Vec3::Zero()); });
        } else {
          across = hierarchies_.pair_candidates([&](ObjectId a, ObjectId b) { return session_.pair_offset(a, b); });
        }
      }
    }
    return across;
  }

  /// The front end: the pending list's, this session's found and this step's object pairs whose fresh swept boxes
  /// overlap (all of them with the front end off).
  std::vector<bvh::TrianglePair> admissible_pairs(const StepView& step, double half, const std::vector<bvh::TrianglePair>& across,
                                                  StepResult& result) {
    const MeshTopology& topology = scene_->topology();
    std::vector<bvh::TrianglePair> admissible;
    const std::array<const std::vector<bvh::TrianglePair>*, 3> lists = {&pending_, &found_, &across};
    {
      ScopedStageTimer timer(result.stages, "front end");
      if (settings_.front_end != FrontEnd::off) {
        // Admissible: the two triangles' fresh swept boxes, widened by δ/2, overlap this step. Each face's box is
        // computed once per step; candidate pairs then only compare two boxes.
        std::vector<Box3> face_boxes(topology.num_faces());
        tbb::parallel_for(std::size_t{0}, topology.num_faces(),
                          [&](std::size_t f) { face_boxes[f] = bvh::swept_face_box(topology.face(static_cast<FaceId>(f)), step.x0, step.x1, half); });
        // The pending list and this step's object pairs are filtered in place of a merged copy: the back end's
        // answer does not depend on the order of its candidates.
        const auto overlapping = [&](const bvh::TrianglePair& pair) { return boxes_overlap(face_boxes[pair.first], face_boxes[pair.second]); };
        for (const auto* list : lists) append_kept(*list, overlapping, admissible);
      } else {
        for (const auto* list : lists) admissible.insert(admissible.end(), list->begin(), list->end());
      }
    }
    return admissible;
  }

  /// First frame of a session: budgets, inflated refit, full self traversal into the pending list.
  void start_session(StepResult& result) {
    const MeshTopology& topology = scene_->topology();
    const double half = scene_->thickness() / 2;
    {
      ScopedStageTimer timer(result.stages, "update");
      anchor_ = relative1_;
      session_.start(relative0_, relative1_, budget_);
      for (ObjectId id = 0; id < scene_->objects().size(); ++id) {
        const SceneObject& object = scene_->object(id);
        if (object.kind == ObjectKind::static_object) continue;
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
      found_.clear();
    }
  }

  /// Enlarges the dangling triangles' leaves to their fresh boxes, then finds every face whose box overlaps one of
  /// them, within what the collision filter allows; new pairs join the pending list (in found_).
  void partial_traversal(const std::vector<FaceId>& dangling_faces, double half) {
    if (dangling_faces.empty()) return;
    const MeshTopology& topology = scene_->topology();
    std::vector<Box3> fresh(dangling_faces.size());
    tbb::parallel_for(std::size_t{0}, dangling_faces.size(),
                      [&](std::size_t i) { fresh[i] = bvh::swept_face_box(topology.face(dangling_faces[i]), relative0_, relative1_, half); });
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
                                                std::span<const Box3>(fresh).subspan(begin, end - begin), hierarchies_.tree(object));
        found.insert(found.end(), pairs.begin(), pairs.end());
      }
      begin = end;
    }
    if (found.empty()) return;
    // The pending list is sorted vectors rather than a hash table: merging sorted runs keeps it duplicate-free,
    // deterministic and compact, and the front end reads it sequentially. The session start's pairs stay as they
    // are; the few new ones are looked up there and merged into found_ (merging all of them into one list each
    // step copied the whole list: 0.5-1.6 ms a step at 319k pending pairs).
    tbb::parallel_sort(found.begin(), found.end());
    found.erase(std::remove_if(found.begin(), found.end(),
                               [&](const bvh::TrianglePair& pair) { return std::binary_search(pending_.begin(), pending_.end(), pair); }),
                found.end());
    std::vector<bvh::TrianglePair> merged;
    merged.reserve(found_.size() + found.size());
    std::set_union(found_.begin(), found_.end(), found.begin(), found.end(), std::back_inserter(merged));
    found_.swap(merged);
  }

  ApccdSettings settings_;
  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase_;
  const Scene* scene_ = nullptr;
  std::vector<AssignmentMask> masks_;
  ObjectHierarchies hierarchies_;
  /// World-frame trees refitted every step for the pairs across objects (fresh_object_pairs).
  ObjectHierarchies fresh_;
  ApccdSession session_;
  /// Positions in each object's frame at the step's ends.
  std::vector<Vec3> relative0_, relative1_;
  std::vector<Vec3> anchor_;
  std::vector<double> budget_;
  /// The pending list: the session start's candidates (sorted), and the pairs the session's partial traversals
  /// found since that are not among them (sorted, no duplicates).
  std::vector<bvh::TrianglePair> pending_, found_;
  ProximityHistory history_;
};

}  // namespace

std::vector<StrategyEntry> apccd_entries() {
  StrategyEntry apccd;
  apccd.name = "apccd";
  apccd.help = "the adaptive pipeline with skipping-frame sessions (Wong, NCS 2009, Algorithm 1)";
  apccd.keys = apccd_keys();
  for (narrowphase::KeySpec& key : backend_keys()) apccd.keys.push_back(std::move(key));
  apccd.backends = {"cpu", "opencl"};
  apccd.make = [](StrategyRequest request) -> std::unique_ptr<Strategy> {
    const ApccdSettings settings = read_apccd_settings(request.keys);
    const BackendChoice backend = read_backend(request.keys);
    if (backend.opencl()) return make_apccd_opencl(settings, std::move(request.narrow_phase), backend);
    return std::make_unique<Apccd>(settings, std::move(request.narrow_phase));
  };
  apccd.check = [](const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase& narrow) {
    read_apccd_settings(keys);
    resolved_backend("apccd", read_backend(keys), narrow, true);
  };
  apccd.resolve = [](const narrowphase::SpecReader& keys, const narrowphase::ResolvedNarrowPhase& narrow) {
    const BackendChoice backend = read_backend(keys);
    const std::string name = apccd_name(read_apccd_settings(keys), narrow.name);
    return name + resolved_backend("apccd", backend, narrow, true);
  };
  return {std::move(apccd)};
}

}  // namespace ccd::strategies
