#include "harness/run/verdict.hpp"

#include "datasets/query_file.hpp"
#include "harness/timed_region.hpp"
#include "strategies/elementary_tests.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <type_traits>

namespace ccd::harness {

using nlohmann::json;

void ToiVerdict::add(const ToiVerdict& other) {
  checked += other.checked;
  late += other.late;
  missing += other.missing;
  error_max = std::max(error_max, other.error_max);
  error_sum += other.error_sum;
  errors.insert(errors.end(), other.errors.begin(), other.errors.end());
}

namespace {

/// Compares the reported TOIs with the truth's exact ones (both lists sorted by pair). The truth holds the largest
/// double not after the exact earliest contact, so a reported double is later than the exact time exactly when it
/// is greater; the error |reported - truth| is the error to within one ulp of the exact time.
template <class Contact>
void compare_tois(const std::vector<Contact>& truth, const std::vector<Contact>& reported, ToiVerdict& verdict) {
  auto at = reported.begin();
  for (const Contact& exact : truth) {
    at = std::lower_bound(at, reported.end(), exact.pair, [](const Contact& c, const auto& pair) { return c.pair < pair; });
    if (at == reported.end()) break;
    if (at->pair != exact.pair) continue;
    if (std::isnan(at->toi)) {
      ++verdict.missing;
      continue;
    }
    ++verdict.checked;
    verdict.late += at->toi > exact.toi ? 1 : 0;
    const double error = std::abs(at->toi - exact.toi);
    verdict.error_max = std::max(verdict.error_max, error);
    verdict.error_sum += error;
    verdict.errors.push_back(error);
  }
}

template <class Pair>
bool in_sorted(const std::vector<Pair>& pairs, const Pair& p) {
  return std::binary_search(pairs.begin(), pairs.end(), p);
}

/// A reported triangle pair is a false alarm when none of its elementary pairs is in the truth.
std::size_t triangle_pair_false_alarms(const Scene& scene, const CollisionSet& truth, const std::vector<bvh::TrianglePair>& triangle_pairs) {
  std::size_t false_alarms = 0;
  for (const auto& [a, b] : triangle_pairs) {
    strategies::TestedPairs contained;
    strategies::append_all_elementary_pairs(scene.topology(), a, b, contained);
    const bool any = std::any_of(contained.vertex_face.begin(), contained.vertex_face.end(), [&](const auto& p) { return truth.contains(p); }) ||
                     std::any_of(contained.edge_edge.begin(), contained.edge_edge.end(), [&](const auto& p) { return truth.contains(p); });
    false_alarms += any ? 0 : 1;
  }
  return false_alarms;
}

/// A missed pair as a query of the rational format, truth 1.
datasets::Query as_query(const std::array<Vec3, 8>& rows) {
  datasets::Query query = datasets::query_of_doubles(rows);
  query.truth = true;
  return query;
}

/// Why a missed pair was missed: the strategy's own explanation (fcl's tests), else "culled" or "tested" (audit).
template <class Pair>
std::string miss_cause(const Pair& pair, const strategies::StrategyEntry& strategy, const strategies::TestedPairs* tested,
                       const std::array<Vec3, 8>& rows) {
  if (strategy.explain_miss) return strategy.explain_miss(rows, std::is_same_v<Pair, VertexFacePair>);
  if (!tested) return "missed";
  const auto& list = [&]() -> const auto& {
    if constexpr (std::is_same_v<Pair, VertexFacePair>)
      return tested->vertex_face;
    else
      return tested->edge_edge;
  }
  ();
  return in_sorted(list, pair) ? "tested" : "culled";
}

}  // namespace

Verdict judge(const Scene& scene, const CollisionSet& truth, const strategies::StepResult& result, strategies::Judging judging,
              const strategies::TestedPairs* tested, bool toi) {
  harness_pass("verification");
  Verdict verdict;
  const CollisionSet& reported = result.collisions;
  if (toi && judging == strategies::Judging::elementary_pairs) {
    compare_tois(truth.vertex_face(), reported.vertex_face(), verdict.toi);
    compare_tois(truth.edge_edge(), reported.edge_edge(), verdict.toi);
    compare_tois(truth.face_shape(), reported.face_shape(), verdict.toi);
  }
  const CollisionSet missed = set_difference(truth, reported);
  verdict.missed = missed.size();
  verdict.missed_face_shape = missed.face_shape().size();
  verdict.false_alarms = judging == strategies::Judging::triangle_pairs ? triangle_pair_false_alarms(scene, truth, result.triangle_pairs)
                                                                        : set_difference(reported, truth).size();
  if (tested) {
    for (const auto& c : missed.vertex_face()) (in_sorted(tested->vertex_face, c.pair) ? verdict.tested : verdict.culled) += 1;
    for (const auto& c : missed.edge_edge()) (in_sorted(tested->edge_edge, c.pair) ? verdict.tested : verdict.culled) += 1;
    for (const auto& c : missed.face_shape()) (in_sorted(tested->face_shape, c.pair) ? verdict.tested : verdict.culled) += 1;
  }
  return verdict;
}

namespace {

template <class Pair>
MissedPair pair_record(const Scene& scene, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, const Pair& pair) {
  const auto rows = pair_rows(scene.topology(), x0, x1, pair);
  MissedPair record;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (int k = 0; k < 3; ++k) record.rows[3 * i + static_cast<std::size_t>(k)] = rows[i][k];
  }
  if constexpr (std::is_same_v<Pair, VertexFacePair>) {
    record.ids = {pair.v, pair.f};
  } else {
    record.vertex_face = false;
    record.ids = {pair.a.v0, pair.a.v1, pair.b.v0, pair.b.v1};
  }
  return record;
}

}  // namespace

MissedPair missed_pair_record(const Scene& scene, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, const VertexFacePair& pair) {
  return pair_record(scene, x0, x1, pair);
}

MissedPair missed_pair_record(const Scene& scene, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, const EdgeEdgePair& pair) {
  return pair_record(scene, x0, x1, pair);
}

std::vector<MissedPair> missed_pair_records(const Scene& scene, const std::vector<Vec3>& x0, const std::vector<Vec3>& x1, const CollisionSet& truth,
                                            const CollisionSet& reported, std::size_t limit) {
  std::vector<MissedPair> records;
  const CollisionSet missed = set_difference(truth, reported);
  for (const auto& c : missed.vertex_face()) {
    if (records.size() >= limit) return records;
    records.push_back(missed_pair_record(scene, x0, x1, c.pair));
  }
  for (const auto& c : missed.edge_edge()) {
    if (records.size() >= limit) return records;
    records.push_back(missed_pair_record(scene, x0, x1, c.pair));
  }
  return records;
}

std::size_t reported_count(const strategies::StepResult& result, strategies::Judging judging) {
  return judging == strategies::Judging::triangle_pairs ? result.triangle_pairs.size() : result.collisions.size();
}

json record_misses(const Scene& scene, const std::vector<std::vector<Vec3>>& frames, const std::vector<CollisionSet>& truth,
                   const std::vector<strategies::StepResult>& results, const std::vector<strategies::TestedPairs>& tested,
                   const strategies::StrategyEntry& strategy, const std::optional<std::filesystem::path>& directory) {
  harness_pass("miss records");
  // A regression library needs a few of each cause, not every one of a strategy that misses thousands.
  constexpr std::size_t kMaxPerFile = 100;
  std::map<std::string, std::vector<datasets::Query>> vf, ee;
  std::map<std::string, std::size_t> counts;
  for (std::size_t k = 0; k < results.size(); ++k) {
    const CollisionSet missed = set_difference(truth[k], results[k].collisions);
    const strategies::TestedPairs* audit = k < tested.size() ? &tested[k] : nullptr;
    auto note = [&](const auto& pair, auto& by_cause) {
      const auto rows = pair_rows(scene.topology(), frames[k], frames[k + 1], pair);
      const std::string cause = miss_cause(pair, strategy, audit, rows);
      ++counts[cause];
      if (by_cause[cause].size() < kMaxPerFile) by_cause[cause].push_back(as_query(rows));
    };
    for (const auto& c : missed.vertex_face()) note(c.pair, vf);
    for (const auto& c : missed.edge_edge()) note(c.pair, ee);
    // A face-shape question has no query-file form (a sphere's is a VF query at R + δ, a box's is 80 of them): its
    // misses are counted by cause, as "face-shape culled" or "face-shape tested".
    for (const auto& c : missed.face_shape()) {
      if (!audit) {
        ++counts["face-shape missed"];
        continue;
      }
      ++counts[in_sorted(audit->face_shape, c.pair) ? "face-shape tested" : "face-shape culled"];
    }
  }
  if (directory) {
    // Every missed pair collides at the scene's δ: the files say their labels are for it.
    for (const auto& [cause, queries] : vf) datasets::write_query_file(*directory / "vertex-face" / (cause + ".csv"), queries, scene.thickness());
    for (const auto& [cause, queries] : ee) datasets::write_query_file(*directory / "edge-edge" / (cause + ".csv"), queries, scene.thickness());
  }
  json causes = json::object();
  for (const auto& [cause, count] : counts) causes[cause] = count;
  return causes;
}

json contact_by_objects(const Scene& scene, const std::vector<CollisionSet>& truth, std::size_t steps) {
  const MeshTopology& topology = scene.topology();
  std::map<std::pair<ObjectId, ObjectId>, std::size_t> pairs, faces;
  for (std::size_t k = 0; k < steps; ++k) {
    std::map<std::pair<ObjectId, ObjectId>, std::set<FaceId>> in_contact;
    auto note = [&](ObjectId a, ObjectId b) {
      ++pairs[{std::min(a, b), std::max(a, b)}];
      return std::pair{std::min(a, b), std::max(a, b)};
    };
    auto add_vertex_faces = [&](std::set<FaceId>& set, VertexId v) {
      for (FaceId f : topology.vertex_faces(v)) set.insert(f);
    };
    for (const auto& c : truth[k].vertex_face()) {
      const ObjectId ov = scene.object_of_vertex(c.pair.v), of = scene.object_of_face(c.pair.f);
      const auto key = note(ov, of);
      if (ov == of) continue;
      if (of == key.first) {
        in_contact[key].insert(c.pair.f);
      } else {
        add_vertex_faces(in_contact[key], c.pair.v);
      }
    }
    for (const auto& c : truth[k].edge_edge()) {
      const ObjectId oa = scene.object_of_vertex(c.pair.a.v0), ob = scene.object_of_vertex(c.pair.b.v0);
      const auto key = note(oa, ob);
      if (oa == ob) continue;
      const Edge e = oa == key.first ? c.pair.a : c.pair.b;
      for (FaceId f : topology.edge_faces(*topology.find_edge(e.v0, e.v1))) in_contact[key].insert(f);
    }
    for (const auto& c : truth[k].face_shape()) in_contact[note(scene.object_of_face(c.pair.f), c.pair.shape)].insert(c.pair.f);
    for (const auto& [key, set] : in_contact) faces[key] += set.size();
  }
  json colliding = json::object(), contact_faces = json::object();
  for (const auto& [key, count] : pairs) {
    const std::string name = scene.object(key.first).name + "/" + scene.object(key.second).name;
    colliding[name] = count;
    if (key.first != key.second) contact_faces[name] = faces[key];
  }
  return {{"colliding_by_objects", colliding}, {"faces_in_contact_by_objects", contact_faces}};
}

}  // namespace ccd::harness
