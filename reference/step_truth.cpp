#include "reference/step_truth.hpp"

#include "core/step.hpp"

#include "reference/elementary_pair.hpp"
#include "reference/face_shape.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>

namespace ccd::reference {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct CertifiedBox {
  std::array<double, 3> lower{kInfinity, kInfinity, kInfinity};
  std::array<double, 3> upper{-kInfinity, -kInfinity, -kInfinity};

  void extend(const CertifiedBox& other) {
    for (int k = 0; k < 3; ++k) {
      lower[k] = std::min(lower[k], other.lower[k]);
      upper[k] = std::max(upper[k], other.upper[k]);
    }
  }
};

/// A vertex's position at time t of the step, t = slice / slices, computed in doubles. At t = 0 and t = 1 it is
/// x0 and x1 themselves (exact); in between, the subtraction, product and sum round by at most 5 units in the
/// last place of the larger coordinate magnitude M, which kSliceRounding (16 units, 2^-49·M) covers.
double position_at(double x0, double x1, std::size_t slice, std::size_t slices) {
  if (slice == 0) return x0;
  if (slice == slices) return x1;
  return x0 + (static_cast<double>(slice) / static_cast<double>(slices)) * (x1 - x0);
}
constexpr double kSliceRounding = 0x1p-49;

/// Each vertex's box over the time slice [slice/slices, (slice+1)/slices] of the step, widened by `half`
/// (>= δ/2) on every side: positions move linearly, so the box of the slice's two end positions holds the whole
/// slice. min/max are exact; the slice's end positions are widened by their rounding bound (none at t = 0 and 1),
/// and every rounded subtraction or addition is moved one more ulp outward, which covers its own rounding.
std::vector<CertifiedBox> vertex_boxes(std::span<const Vec3> x0, std::span<const Vec3> x1, double half, std::size_t slice, std::size_t slices) {
  std::vector<CertifiedBox> boxes(x0.size());
  const bool whole_step = slices == 1;
  tbb::parallel_for(std::size_t{0}, x0.size(), [&](std::size_t v) {
    for (int k = 0; k < 3; ++k) {
      const double a = position_at(x0[v][k], x1[v][k], slice, slices);
      const double b = position_at(x0[v][k], x1[v][k], slice + 1, slices);
      const double rounding = whole_step ? 0.0 : kSliceRounding * std::max(std::abs(x0[v][k]), std::abs(x1[v][k]));
      const double widen = half + rounding;
      const double lo = std::min(a, b);
      const double hi = std::max(a, b);
      boxes[v].lower[k] = widen == 0.0 ? lo : std::nextafter(std::nextafter(lo - widen, -kInfinity), -kInfinity);
      boxes[v].upper[k] = widen == 0.0 ? hi : std::nextafter(std::nextafter(hi + widen, kInfinity), kInfinity);
    }
  });
  return boxes;
}

/// How many time slices the enumeration uses: when vertices move much farther in a step than a primitive is long
/// (cloth falling at resolution 100 moves 5 to 8 edge lengths per step), whole-step boxes overlap dozens of
/// unrelated primitives along the motion, and the decisions dominate; boxes per slice are as short as the motion
/// in the slice. Measured on funnel at resolution 100 (step 16, 57.7 million whole-step pairs): see the commit.
/// A power of two from 1 to 8: the largest displacement of any coordinate over the mean edge extent.
std::size_t slice_count(const MeshTopology& topology, std::span<const Vec3> x0, std::span<const Vec3> x1) {
  double largest_motion = 0.0, edge_extent = 0.0;
  for (VertexId v = 0; v < topology.num_vertices(); ++v) {
    if (topology.is_used(v)) largest_motion = std::max(largest_motion, (x1[v] - x0[v]).cwiseAbs().maxCoeff());
  }
  for (EdgeId e = 0; e < topology.num_edges(); ++e) {
    edge_extent += (x0[topology.edge(e).v1] - x0[topology.edge(e).v0]).cwiseAbs().maxCoeff();
  }
  if (topology.num_edges() == 0 || !(edge_extent > 0)) return 1;
  edge_extent /= static_cast<double>(topology.num_edges());
  std::size_t slices = 1;
  while (slices < 8 && largest_motion > static_cast<double>(slices) * edge_extent) slices *= 2;
  return slices;
}

bool overlap_on(const CertifiedBox& a, const CertifiedBox& b, int axis) { return a.lower[axis] <= b.upper[axis] && b.lower[axis] <= a.upper[axis]; }

/// A box in the sweep: `kind` 0 or 1 tells the two families apart (vertex/face, or edge/edge where both are 0).
struct SweepEntry {
  CertifiedBox box;
  std::uint32_t id;
  std::uint8_t kind;
};

int axis_of_largest_extent(const std::vector<CertifiedBox>& boxes) {
  CertifiedBox all;
  for (const CertifiedBox& b : boxes) all.extend(b);
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (all.upper[k] - all.lower[k] > all.upper[axis] - all.lower[axis]) axis = k;
  }
  return axis;
}

/// Sort-and-sweep: every pair of entries whose boxes overlap, reported once as (i, j) by `emit(a, b)` with
/// a before b in sorted order. `emit` must be thread-safe per thread (it receives a thread-local sink).
template <class Pair, class Emit>
std::vector<Pair> sweep(std::vector<SweepEntry> entries, int axis, Emit emit) {
  tbb::parallel_sort(entries.begin(), entries.end(), [axis](const SweepEntry& a, const SweepEntry& b) {
    if (a.box.lower[axis] != b.box.lower[axis]) return a.box.lower[axis] < b.box.lower[axis];
    return std::pair(a.kind, a.id) < std::pair(b.kind, b.id);
  });
  const int other1 = (axis + 1) % 3, other2 = (axis + 2) % 3;
  tbb::enumerable_thread_specific<std::vector<Pair>> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, entries.size(), 256), [&](const auto& range) {
    std::vector<Pair>& sink = found.local();
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const SweepEntry& a = entries[i];
      for (std::size_t j = i + 1; j < entries.size() && entries[j].box.lower[axis] <= a.box.upper[axis]; ++j) {
        const SweepEntry& b = entries[j];
        if (overlap_on(a.box, b.box, other1) && overlap_on(a.box, b.box, other2)) emit(a, b, sink);
      }
    }
  });
  std::vector<Pair> pairs;
  for (const auto& local : found) pairs.insert(pairs.end(), local.begin(), local.end());
  tbb::parallel_sort(pairs.begin(), pairs.end());
  return pairs;
}

double milliseconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

struct SlicePairs {
  std::vector<VertexFacePair> vertex_face;
  std::vector<EdgeEdgePair> edge_edge;
};

/// The pairs whose boxes (built from these vertex boxes) overlap and that the scene lets collide, sorted.
SlicePairs slice_pairs(const Scene& scene, const std::vector<CertifiedBox>& boxes) {
  const MeshTopology& topology = scene.topology();
  const int axis = axis_of_largest_extent(boxes);

  std::vector<SweepEntry> vf_entries;
  for (VertexId v = 0; v < topology.num_vertices(); ++v) {
    if (topology.is_used(v)) vf_entries.push_back({boxes[v], v, 0});
  }
  std::vector<SweepEntry> ee_entries;
  for (FaceId f = 0; f < topology.num_faces(); ++f) {
    CertifiedBox box;
    for (VertexId v : topology.face(f)) box.extend(boxes[v]);
    vf_entries.push_back({box, f, 1});
  }
  for (EdgeId e = 0; e < topology.num_edges(); ++e) {
    CertifiedBox box = boxes[topology.edge(e).v0];
    box.extend(boxes[topology.edge(e).v1]);
    ee_entries.push_back({box, e, 0});
  }

  SlicePairs found;
  found.vertex_face =
      sweep<VertexFacePair>(std::move(vf_entries), axis, [&](const SweepEntry& a, const SweepEntry& b, std::vector<VertexFacePair>& sink) {
        if (a.kind == b.kind) return;
        const VertexId v = a.kind == 0 ? a.id : b.id;
        const FaceId f = a.kind == 0 ? b.id : a.id;
        const Face& face = topology.face(f);
        if (v == face[0] || v == face[1] || v == face[2]) return;
        if (!scene.may_collide(scene.object_of_vertex(v), scene.object_of_face(f))) return;
        sink.push_back({v, f});
      });
  found.edge_edge = sweep<EdgeEdgePair>(std::move(ee_entries), axis, [&](const SweepEntry& a, const SweepEntry& b, std::vector<EdgeEdgePair>& sink) {
    const Edge& ea = topology.edge(a.id);
    const Edge& eb = topology.edge(b.id);
    if (shares_vertex(ea, eb)) return;
    if (!scene.may_collide(scene.object_of_vertex(ea.v0), scene.object_of_vertex(eb.v0))) return;
    sink.push_back(make_edge_edge_pair(ea, eb));
  });
  return found;
}

/// The face-shape pairs whose boxes overlap in this slice and that the scene lets collide, sorted. A shape's box is
/// its centre's slice box (already widened by δ/2) grown by R or by the half extents, each bound moved one ulp
/// outward to cover its rounding; a face's box is its corners' boxes (widened by δ/2): a face within δ of the
/// shape at some time of the slice has a box that meets the shape's.
std::vector<FaceShapePair> slice_face_shape_pairs(const Scene& scene, const std::vector<CertifiedBox>& boxes) {
  std::vector<FaceShapePair> pairs;
  const MeshTopology& topology = scene.topology();
  for (const ObjectId s : scene.shape_objects()) {
    const SceneObject& shape_object = scene.object(s);
    const Shape& shape = *shape_object.shape;
    CertifiedBox shape_box = boxes[shape_object.first_vertex];
    for (int k = 0; k < 3; ++k) {
      const double grow = shape.kind == ShapeKind::sphere ? shape.radius : shape.half_extents[k];
      shape_box.lower[k] = std::nextafter(shape_box.lower[k] - grow, -kInfinity);
      shape_box.upper[k] = std::nextafter(shape_box.upper[k] + grow, kInfinity);
    }
    for (ObjectId o = 0; o < scene.objects().size(); ++o) {
      const SceneObject& object = scene.object(o);
      if (o == s || object.num_faces == 0 || !scene.may_collide(o, s)) continue;
      for (FaceId f = object.first_face; f < object.first_face + object.num_faces; ++f) {
        CertifiedBox box;
        for (VertexId v : topology.face(f)) box.extend(boxes[v]);
        if (overlap_on(box, shape_box, 0) && overlap_on(box, shape_box, 1) && overlap_on(box, shape_box, 2)) pairs.push_back({f, s});
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace

StepTruth compute_step_truth(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1, const TruthRequest& request) {
  const MeshTopology& topology = scene.topology();
  StepTruth truth;
  const auto enumeration_start = std::chrono::steady_clock::now();

  // δ/2, rounded up so that two half-widths always cover δ.
  const double half = request.thickness == 0.0 ? 0.0 : std::nextafter(request.thickness / 2, kInfinity);
  const std::size_t slices = request.time_slices > 0 ? request.time_slices : slice_count(topology, x0, x1);
  // A pair that comes within δ at time t does so inside some slice, where both primitives' slice boxes hold them:
  // the union over slices misses nothing.
  std::vector<VertexFacePair> vf_pairs;
  std::vector<EdgeEdgePair> ee_pairs;
  std::vector<FaceShapePair> fs_pairs;
  for (std::size_t slice = 0; slice < slices; ++slice) {
    const std::vector<CertifiedBox> boxes = vertex_boxes(x0, x1, half, slice, slices);
    const SlicePairs found = slice_pairs(scene, boxes);
    vf_pairs.insert(vf_pairs.end(), found.vertex_face.begin(), found.vertex_face.end());
    ee_pairs.insert(ee_pairs.end(), found.edge_edge.begin(), found.edge_edge.end());
    if (!scene.shape_objects().empty()) {
      const std::vector<FaceShapePair> shape_pairs = slice_face_shape_pairs(scene, boxes);
      fs_pairs.insert(fs_pairs.end(), shape_pairs.begin(), shape_pairs.end());
    }
  }
  if (slices > 1) {
    tbb::parallel_sort(vf_pairs.begin(), vf_pairs.end());
    vf_pairs.erase(std::unique(vf_pairs.begin(), vf_pairs.end()), vf_pairs.end());
    tbb::parallel_sort(ee_pairs.begin(), ee_pairs.end());
    ee_pairs.erase(std::unique(ee_pairs.begin(), ee_pairs.end()), ee_pairs.end());
    std::sort(fs_pairs.begin(), fs_pairs.end());
    fs_pairs.erase(std::unique(fs_pairs.begin(), fs_pairs.end()), fs_pairs.end());
  }
  truth.statistics.time_slices = slices;
  truth.statistics.vertex_face_pairs = vf_pairs.size();
  truth.statistics.edge_edge_pairs = ee_pairs.size();
  truth.statistics.face_shape_pairs = fs_pairs.size();
  truth.statistics.enumeration_milliseconds = milliseconds_since(enumeration_start);

  const auto decision_start = std::chrono::steady_clock::now();
  const DecisionRequest decision_request{true, request.with_toi, 64};
  struct Local {
    CollisionSet collisions;
    std::size_t by_filter = 0;
    std::size_t exactly = 0;
  };
  tbb::enumerable_thread_specific<Local> locals;
  auto record = [&](Local& local, const Decision& decision, const auto& pair) {
    (decision.decided_by == DecidedBy::filter ? local.by_filter : local.exactly) += 1;
    if (!decision.collides) return;
    double toi = kNoToi;
    if (decision.toi_floor) toi = *decision.toi_floor;
    local.collisions.add(pair, toi);
  };
  const std::size_t total = vf_pairs.size() + ee_pairs.size() + fs_pairs.size();
  // Batches let the calling thread report progress between them.
  const std::size_t batch = std::max<std::size_t>(4096, total / 50);
  for (std::size_t begin = 0; begin < total; begin += batch) {
    const std::size_t end = std::min(total, begin + batch);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 64), [&](const auto& range) {
      Local& local = locals.local();
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (i < vf_pairs.size()) {
          const VertexFacePair& pair = vf_pairs[i];
          record(local, decide(PairKind::vertex_face, pair_rows(scene.topology(), x0, x1, pair), request.thickness, decision_request), pair);
        } else if (i < vf_pairs.size() + ee_pairs.size()) {
          const EdgeEdgePair& pair = ee_pairs[i - vf_pairs.size()];
          record(local, decide(PairKind::edge_edge, pair_rows(scene.topology(), x0, x1, pair), request.thickness, decision_request), pair);
        } else {
          const FaceShapePair& pair = fs_pairs[i - vf_pairs.size() - ee_pairs.size()];
          record(local, decide_face_shape(*scene.object(pair.shape).shape, face_shape_rows(scene, x0, x1, pair), request.thickness, decision_request),
                 pair);
        }
      }
    });
    if (request.progress) request.progress(end, total);
  }
  for (const Local& local : locals) {
    truth.collisions.append(local.collisions);
    truth.statistics.decided_by_filter += local.by_filter;
    truth.statistics.decided_exactly += local.exactly;
  }
  truth.collisions.normalize();
  truth.statistics.decision_milliseconds = milliseconds_since(decision_start);
  return truth;
}

}  // namespace ccd::reference
