#include "reference/step_truth.hpp"

#include "core/step.hpp"

#include "reference/elementary_pair.hpp"

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

/// Each vertex's box over x0 and x1 widened by `half` (>= δ/2) on every side. min/max are exact; the one
/// rounded subtraction or addition is then moved one more ulp outward, which covers its rounding error.
std::vector<CertifiedBox> vertex_boxes(std::span<const Vec3> x0, std::span<const Vec3> x1, double half) {
  std::vector<CertifiedBox> boxes(x0.size());
  tbb::parallel_for(std::size_t{0}, x0.size(), [&](std::size_t v) {
    for (int k = 0; k < 3; ++k) {
      const double lo = std::min(x0[v][k], x1[v][k]);
      const double hi = std::max(x0[v][k], x1[v][k]);
      boxes[v].lower[k] = half == 0.0 ? lo : std::nextafter(lo - half, -kInfinity);
      boxes[v].upper[k] = half == 0.0 ? hi : std::nextafter(hi + half, kInfinity);
    }
  });
  return boxes;
}

bool overlap_on(const CertifiedBox& a, const CertifiedBox& b, int axis) {
  return a.lower[axis] <= b.upper[axis] && b.lower[axis] <= a.upper[axis];
}

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

}  // namespace

StepTruth compute_step_truth(const Scene& scene, std::span<const Vec3> x0, std::span<const Vec3> x1,
                             const TruthRequest& request) {
  const MeshTopology& topology = scene.topology();
  StepTruth truth;
  const auto enumeration_start = std::chrono::steady_clock::now();

  // δ/2, rounded up so that two half-widths always cover δ.
  const double half = request.thickness == 0.0 ? 0.0 : std::nextafter(request.thickness / 2, kInfinity);
  const std::vector<CertifiedBox> boxes = vertex_boxes(x0, x1, half);
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

  const std::vector<VertexFacePair> vf_pairs = sweep<VertexFacePair>(
      std::move(vf_entries), axis, [&](const SweepEntry& a, const SweepEntry& b, std::vector<VertexFacePair>& sink) {
        if (a.kind == b.kind) return;
        const VertexId v = a.kind == 0 ? a.id : b.id;
        const FaceId f = a.kind == 0 ? b.id : a.id;
        const Face& face = topology.face(f);
        if (v == face[0] || v == face[1] || v == face[2]) return;
        if (!scene.may_collide(scene.object_of_vertex(v), scene.object_of_face(f))) return;
        sink.push_back({v, f});
      });
  const std::vector<EdgeEdgePair> ee_pairs = sweep<EdgeEdgePair>(
      std::move(ee_entries), axis, [&](const SweepEntry& a, const SweepEntry& b, std::vector<EdgeEdgePair>& sink) {
        const Edge& ea = topology.edge(a.id);
        const Edge& eb = topology.edge(b.id);
        if (shares_vertex(ea, eb)) return;
        if (!scene.may_collide(scene.object_of_vertex(ea.v0), scene.object_of_vertex(eb.v0))) return;
        sink.push_back(make_edge_edge_pair(ea, eb));
      });
  truth.statistics.vertex_face_pairs = vf_pairs.size();
  truth.statistics.edge_edge_pairs = ee_pairs.size();
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
    if (decision.toi) toi = mpq_class((decision.toi->lower + decision.toi->upper) / 2).get_d();
    local.collisions.add(pair, toi);
  };
  const std::size_t total = vf_pairs.size() + ee_pairs.size();
  // Batches let the calling thread report progress between them.
  const std::size_t batch = std::max<std::size_t>(4096, total / 50);
  for (std::size_t begin = 0; begin < total; begin += batch) {
    const std::size_t end = std::min(total, begin + batch);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(begin, end, 64), [&](const auto& range) {
      Local& local = locals.local();
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (i < vf_pairs.size()) {
          const VertexFacePair& pair = vf_pairs[i];
          record(local,
                 decide(PairKind::vertex_face, pair_rows(scene.topology(), x0, x1, pair), request.thickness, decision_request),
                 pair);
        } else {
          const EdgeEdgePair& pair = ee_pairs[i - vf_pairs.size()];
          record(local, decide(PairKind::edge_edge, pair_rows(scene.topology(), x0, x1, pair), request.thickness, decision_request),
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
