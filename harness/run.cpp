#include "harness/run.hpp"

#include "ccd/config.hpp"
#include "ccd/git_revision.hpp"
#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/procedural_scenes.hpp"
#include "datasets/scene_file.hpp"
#include "harness/cell_store.hpp"
#include "harness/json_output.hpp"
#include "harness/statistics.hpp"
#include "harness/truth_cache.hpp"
#include "harness/work_queue.hpp"
#include "datasets/query_file.hpp"
#include "strategies/elementary_tests.hpp"
#if CCDBENCH_WITH_FCL
#include "strategies/fcl/fcl_elementary.hpp"
#endif
#include "strategies/strategy.hpp"

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <list>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <tuple>
#include <unistd.h>

namespace ccd::harness {
namespace {

using nlohmann::json;

SceneSource generated(const std::string& name, std::map<std::string, double> parameters) {
  std::ostringstream label;
  label << name << "-r" << parameters.at("resolution") << "-f" << parameters.at("frames");
  if (const auto it = parameters.find("steps_per_frame"); it != parameters.end() && it->second != 1) label << "-s" << it->second;
  if (const auto it = parameters.find("obstacles"); it != parameters.end() && it->second == 1) label << "-shapes";
  return {label.str(), [name, parameters] {
            json block = {{"name", name}};
            for (const auto& [key, value] : parameters) block[key] = value;
            return datasets::scene_from_json({{"generator", block}}, ".", "suite scene " + name);
          }};
}

/// The worker threads this process may use (--threads, or every core).
std::size_t worker_threads() {
  return std::min<std::size_t>(static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()),
                               tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

/// What every record carries: machine, build type, thread count, git revision, the executable's digest.
json environment() {
  static const json cached = [] {
    char host[256] = {};
    ::gethostname(host, sizeof host - 1);
    std::string cpu = "unknown";
    std::ifstream cpuinfo("/proc/cpuinfo");
    for (std::string line; std::getline(cpuinfo, line);) {
      if (line.rfind("model name", 0) == 0) {
        cpu = line.substr(line.find(':') + 2);
        break;
      }
    }
    const std::string revision = CCDBENCH_GIT_REVISION;  // of the build, not of the source folder at run time
    return json{{"machine", std::string(host) + " (" + cpu + ", " + std::to_string(::sysconf(_SC_NPROCESSORS_ONLN)) + " cores)"},
                {"build_type", CCDBENCH_BUILD_TYPE},
                {"git_revision", revision},
                {"executable", executable_digest()}};
  }();
  json env = cached;
  env["threads"] = worker_threads();
  env["rank"] = rank_info().rank;
  return env;
}

/// "2026-11-22T21:30:00.123456Z": orders the cells of results.jsonl by when they finished.
std::string utc_now() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto micros = std::chrono::duration_cast<std::chrono::microseconds>(now.time_since_epoch()).count() % 1000000;
  std::tm utc{};
  ::gmtime_r(&seconds, &utc);
  char text[64];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%06lldZ", utc.tm_year + 1900, utc.tm_mon + 1,
                utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, static_cast<long long>(micros));
  return text;
}

/// TOI accuracy over the truth pairs a strategy reported: `checked` carried a TOI, `missing` did not.
struct ToiVerdict {
  std::size_t checked = 0, late = 0, missing = 0;
  double error_max = 0, error_sum = 0;

  void add(const ToiVerdict& other) {
    checked += other.checked;
    late += other.late;
    missing += other.missing;
    error_max = std::max(error_max, other.error_max);
    error_sum += other.error_sum;
  }
};

/// Misses and false alarms of one step; misses split by whether the strategy tested the pair.
struct Verdict {
  std::size_t missed = 0, culled = 0, tested = 0, false_alarms = 0;
  /// Of `missed`: face-shape pairs.
  std::size_t missed_face_shape = 0;
  ToiVerdict toi;
};

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
  }
}

template <class Pair>
bool in_sorted(const std::vector<Pair>& pairs, const Pair& p) {
  return std::binary_search(pairs.begin(), pairs.end(), p);
}

/// A reported triangle pair is a false alarm when none of its elementary pairs is in the truth.
std::size_t triangle_pair_false_alarms(const Scene& scene, const CollisionSet& truth,
                                       const std::vector<bvh::TrianglePair>& triangle_pairs) {
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

/// Judges one step (DESIGN.md §1, §3). A strategy judged by triangle pairs reports in `collisions` every
/// elementary pair its triangle pairs contain, so misses are computed alike; its false alarms are triangle pairs.
Verdict judge(const Scene& scene, const CollisionSet& truth, const strategies::StepResult& result,
              strategies::Judging judging, const strategies::TestedPairs* tested, bool toi) {
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
  verdict.false_alarms = judging == strategies::Judging::triangle_pairs
                             ? triangle_pair_false_alarms(scene, truth, result.triangle_pairs)
                             : set_difference(reported, truth).size();
  if (tested) {
    for (const auto& c : missed.vertex_face()) (in_sorted(tested->vertex_face, c.pair) ? verdict.tested : verdict.culled) += 1;
    for (const auto& c : missed.edge_edge()) (in_sorted(tested->edge_edge, c.pair) ? verdict.tested : verdict.culled) += 1;
    for (const auto& c : missed.face_shape()) (in_sorted(tested->face_shape, c.pair) ? verdict.tested : verdict.culled) += 1;
  }
  return verdict;
}

/// What a step reported, in the unit it is judged by.
std::size_t reported_count(const strategies::StepResult& result, strategies::Judging judging) {
  return judging == strategies::Judging::triangle_pairs ? result.triangle_pairs.size() : result.collisions.size();
}

struct SceneData {
  std::string label;
  datasets::SceneSequence sequence;
  std::vector<std::vector<Vec3>> frames;
  std::vector<CollisionSet> truth;  // per step, when verifying
  std::vector<bool> has_truth;      // which steps' truth this rank holds
  std::size_t steps = 0;            // the steps run (--max-steps may cut the scene's)
};

datasets::Query as_query(const std::array<Vec3, 8>& rows) {
  datasets::Query query;
  for (int i = 0; i < 8; ++i) {
    for (int k = 0; k < 3; ++k) query.exact[i][k] = mpq_class(rows[i][k]);
  }
  query.rounded = rows;
  query.truth = true;
  return query;
}

/// Why a missed pair was missed: "culled" or "tested" (audit), or for FCL's own tests the cause of its "no"
/// (strategies/fcl/fcl_elementary.hpp).
template <class Pair>
std::string miss_cause(const Pair& pair, bool fcl, const strategies::TestedPairs* tested, const std::array<Vec3, 8>& rows) {
#if CCDBENCH_WITH_FCL
  if (fcl) return std::string(to_string(strategies::explain_fcl_answer(rows, std::is_same_v<Pair, VertexFacePair>)));
#else
  (void)fcl;
  (void)rows;
#endif
  if (!tested) return "missed";
  const auto& list = [&]() -> const auto& {
    if constexpr (std::is_same_v<Pair, VertexFacePair>) return tested->vertex_face; else return tested->edge_edge;
  }();
  return in_sorted(list, pair) ? "tested" : "culled";
}

/// Counts each step's misses by cause and, with `directory`, writes them as query files (truth 1) under
/// DIRECTORY/vertex-face/CAUSE.csv and DIRECTORY/edge-edge/CAUSE.csv (at most kMaxPerFile each), so a miss can be
/// replayed with `ccdbench queries` and kept in a regression library.
json record_misses(const Scene& scene, const std::vector<std::vector<Vec3>>& frames, const std::vector<CollisionSet>& truth,
                   const std::vector<strategies::StepResult>& results, const std::vector<strategies::TestedPairs>& tested,
                   bool fcl, const std::optional<std::filesystem::path>& directory) {
  constexpr std::size_t kMaxPerFile = 100;
  std::map<std::string, std::vector<datasets::Query>> vf, ee;
  std::map<std::string, std::size_t> counts;
  for (std::size_t k = 0; k < results.size(); ++k) {
    const CollisionSet missed = set_difference(truth[k], results[k].collisions);
    const strategies::TestedPairs* audit = k < tested.size() ? &tested[k] : nullptr;
    auto note = [&](const auto& pair, auto& by_cause) {
      const auto rows = pair_rows(scene.topology(), frames[k], frames[k + 1], pair);
      const std::string cause = miss_cause(pair, fcl, audit, rows);
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
    for (const auto& [cause, queries] : vf) datasets::write_query_file(*directory / "vertex-face" / (cause + ".csv"), queries);
    for (const auto& [cause, queries] : ee) datasets::write_query_file(*directory / "edge-edge" / (cause + ".csv"), queries);
  }
  json causes = json::object();
  for (const auto& [cause, count] : counts) causes[cause] = count;
  return causes;
}

/// Contact between objects, over every step's truth: per object pair "A/B" (A declared first; "A/A" for self
/// contact), the colliding pairs, and the faces of A in contact with B (a face is in contact when one of its corners,
/// edges or itself is in a colliding pair with B: the faces that a face-shape pair would name), summed over steps.
/// What reports/shapes compares between obstacles=mesh and obstacles=shape.
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

/// Runs one cell: repeats timed passes, judges the first against the truth, audits only when something is missed.
json run_cell(const SceneData& data, const std::string& spec, const RunOptions& options, std::size_t steps,
             const std::string& cell_name) {
  const Scene& scene = data.sequence.scene();
  std::vector<std::vector<double>> step_ms(steps);
  std::map<std::string, std::vector<double>> stage_ms;
  std::vector<strategies::StepResult> first_pass;
  std::string resolved;
  strategies::Judging judging = strategies::Judging::elementary_pairs;
  for (int repeat = 0; repeat < std::max(1, options.repeats); ++repeat) {
    auto strategy = strategies::make_strategy(spec);
    resolved = strategy->name();
    judging = strategy->judging();
    strategy->init(scene, data.frames[0]);
    for (std::size_t k = 0; k < steps; ++k) {
      const StepView view{&scene, k, data.frames[k], data.frames[k + 1]};
      const auto start = std::chrono::steady_clock::now();
      strategies::StepResult result = strategy->step(view, false);
      step_ms[k].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      for (const auto& [stage, ms] : result.stages.entries()) stage_ms[stage].push_back(ms);
      if (repeat == 0) first_pass.push_back(std::move(result));
    }
    std::cerr << "run: " << data.label << " / " << resolved << ": pass " << repeat + 1 << " of " << options.repeats << " done\n";
  }
  std::vector<Verdict> verdicts(steps);
  std::vector<strategies::TestedPairs> audited;
  json miss_causes = json::object();
  if (options.verify) {
    bool any_missed = false;
    for (std::size_t k = 0; k < steps; ++k) {
      verdicts[k] = judge(scene, data.truth[k], first_pass[k], judging, nullptr, options.toi);
      any_missed = any_missed || verdicts[k].missed > 0;
    }
    if (any_missed) {
      // Audit pass, outside every timed region: which misses were never tested (culled) and which tested wrong.
      auto strategy = strategies::make_strategy(spec);
      strategy->init(scene, data.frames[0]);
      for (std::size_t k = 0; k < steps; ++k) {
        const strategies::StepResult audit = strategy->step({&scene, k, data.frames[k], data.frames[k + 1]}, true);
        if (!audit.collisions.same_pairs(first_pass[k].collisions)) {
          throw std::runtime_error(resolved + " gave different answers on two runs of step " + std::to_string(k) +
                                   " of " + data.label + ": the strategy is not deterministic");
        }
        verdicts[k] = judge(scene, data.truth[k], first_pass[k], judging, &*audit.tested, options.toi);
        audited.push_back(std::move(*audit.tested));
      }
      const bool fcl = resolved.rfind("fcl:", 0) == 0;
      std::optional<std::filesystem::path> directory;
      if (options.misses) directory = *options.misses / safe_path_component(data.label) / std::filesystem::path(cell_name).stem();
      miss_causes = record_misses(scene, data.frames, data.truth, first_pass, audited, fcl, directory);
    }
  }
  json step_records = json::array();
  std::vector<double> medians;
  std::size_t colliding = 0, reported = 0, missed = 0, culled = 0, tested = 0, false_alarms = 0;
  std::size_t colliding_face_shape = 0, missed_face_shape = 0;
  ToiVerdict toi_total;
  double candidates = 0, tests = 0, history = 0;
  // Each strategy counter (apccd's session_start, nf, pending_pairs, ...) over the steps: mean and max, since the
  // paper reports averages and peaks, in the order the strategy reports them.
  std::vector<std::pair<std::string, std::pair<double, double>>> counter_totals;
  for (std::size_t k = 0; k < steps; ++k) {
    const strategies::StepResult& r = first_pass[k];
    const double ms = median(step_ms[k]);
    medians.push_back(ms);
    json stages = json::object();
    for (const auto& [stage, value] : r.stages.entries()) stages[stage] = value;
    json record = {{"record", "step"},
                   {"scene", data.label},
                   {"strategy", resolved},
                   {"step", k},
                   {"ms", ms},
                   {"stages", stages},
                   {"candidate_pairs", r.counters.candidate_triangle_pairs},
                   {"elementary_tests", r.counters.elementary_tests},
                   {"history_bytes", r.counters.history_bytes},
                   {"reported", reported_count(r, judging)}};
    // The digest of the answers (pairs and TOI bits), to compare two runs step by step; fcl's cells are judged by
    // triangle pairs and carry none.
    if (judging == strategies::Judging::elementary_pairs) record["answers"] = answers_digest(r.collisions);
    for (const auto& [name, value] : r.counters.extra) {
      record[name] = value;
      auto it = std::find_if(counter_totals.begin(), counter_totals.end(), [&](const auto& entry) { return entry.first == name; });
      if (it == counter_totals.end()) it = counter_totals.insert(counter_totals.end(), {name, {0.0, value}});
      it->second.first += value;
      it->second.second = std::max(it->second.second, value);
    }
    if (options.verify) {
      record["colliding"] = data.truth[k].size();
      if (!scene.shape_objects().empty()) {
        record["colliding_face_shape"] = data.truth[k].face_shape().size();
        record["missed_face_shape"] = verdicts[k].missed_face_shape;
      }
      record["missed"] = verdicts[k].missed;
      record["missed_culled"] = verdicts[k].culled;
      record["missed_tested"] = verdicts[k].tested;
      record["false_alarms"] = verdicts[k].false_alarms;
      if (options.toi) {
        record["toi_checked"] = verdicts[k].toi.checked;
        record["toi_late"] = verdicts[k].toi.late;
        record["toi_error_max"] = verdicts[k].toi.error_max;
      }
      colliding += data.truth[k].size();
      colliding_face_shape += data.truth[k].face_shape().size();
      missed_face_shape += verdicts[k].missed_face_shape;
      toi_total.add(verdicts[k].toi);
    }
    reported += reported_count(r, judging);
    missed += verdicts[k].missed;
    culled += verdicts[k].culled;
    tested += verdicts[k].tested;
    false_alarms += verdicts[k].false_alarms;
    candidates += static_cast<double>(r.counters.candidate_triangle_pairs);
    tests += static_cast<double>(r.counters.elementary_tests);
    history = std::max(history, static_cast<double>(r.counters.history_bytes));
    record.update(environment());
    step_records.push_back(record);
  }
  json stage_summary = json::object();
  // Mean per step too (a step without the stage adds 0): they add up to ms_per_step_mean, so a session's cheap
  // frames and its expensive start are both in them (apccd's medians show one or the other).
  json stage_mean = json::object();
  const double timed_steps = static_cast<double>(std::max<std::size_t>(steps, 1) * static_cast<std::size_t>(std::max(1, options.repeats)));
  for (const auto& [stage, values] : stage_ms) {
    stage_summary[stage] = median(values);
    double sum = 0;
    for (const double ms : values) sum += ms;
    stage_mean[stage] = sum / timed_steps;
  }
  json counter_summary = json::object();
  for (const auto& [name, total] : counter_totals) {
    counter_summary[name] = {{"mean", total.first / static_cast<double>(std::max<std::size_t>(steps, 1))}, {"max", total.second}};
  }
  double ms_sum = 0;
  for (const double ms : medians) ms_sum += ms;
  json summary = {{"record", "summary"},
                  {"scene", data.label},
                  {"strategy", resolved},
                  {"triangles", scene.topology().num_faces()},
                  {"vertices", scene.topology().num_vertices()},
                  {"steps", steps},
                  {"thickness", scene.thickness()},
                  {"ms_per_step", median(medians)},
                  {"ms_per_step_mean", ms_sum / static_cast<double>(std::max<std::size_t>(steps, 1))},
                  {"stage_ms", stage_summary},
                  {"stage_ms_mean", stage_mean},
                  {"counters", counter_summary},
                  {"candidate_pairs", candidates / static_cast<double>(std::max<std::size_t>(steps, 1))},
                  {"elementary_tests", tests / static_cast<double>(std::max<std::size_t>(steps, 1))},
                  {"history_bytes", history},
                  {"reported", reported},
                  {"judged_by", judging == strategies::Judging::triangle_pairs ? "triangle pairs" : "elementary pairs"},
                  {"thickness_from", options.thickness ? "command line" : "scene"},
                  {"verified", options.verify},
                  {"repeats", options.repeats},
                  {"cell", std::filesystem::path(cell_name).stem().string()},
                  {"finished_at", utc_now()}};
  if (options.verify) {
    summary.update(json{{"colliding", colliding},
                        {"missed", missed},
                        {"missed_culled", culled},
                        {"missed_tested", tested},
                        {"false_alarms", false_alarms},
                        {"miss_causes", miss_causes}});
    summary.update(contact_by_objects(scene, data.truth, steps));
    if (!scene.shape_objects().empty()) {
      summary.update(json{{"colliding_face_shape", colliding_face_shape}, {"missed_face_shape", missed_face_shape}});
    }
    if (options.toi) {
      summary.update(json{{"toi_checked", toi_total.checked},
                          {"toi_late", toi_total.late},
                          {"toi_missing", toi_total.missing},
                          {"toi_error_max", toi_total.error_max},
                          {"toi_error_mean", toi_total.checked ? toi_total.error_sum / static_cast<double>(toi_total.checked) : 0.0}});
    }
  }
  summary.update(environment());
  return {{"summary", summary}, {"steps", step_records}};
}

std::string format(double value, int precision) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(precision) << value;
  return out.str();
}

constexpr const char* kTrianglePairMark = " (†)";
constexpr const char* kTrianglePairNote =
    "(†) judged by triangle pairs at δ = 0 (DESIGN.md §3): a truth pair counts as found when a reported triangle pair "
    "contains both its primitives; false alarms are reported triangle pairs that contain no colliding pair.\n";

/// The footnotes the rows need.
std::string table_notes(const std::vector<std::vector<std::string>>& rows) {
  const bool any = std::any_of(rows.begin(), rows.end(), [](const auto& row) { return row[3].find(kTrianglePairMark) != std::string::npos; });
  return any ? kTrianglePairNote : "";
}

/// The table rows, speed-ups only between cells of this invocation (DESIGN.md §5).
std::vector<std::vector<std::string>> table_rows(const std::vector<json>& summaries) {
  std::vector<std::vector<std::string>> rows;
  const bool with_toi = std::any_of(summaries.begin(), summaries.end(), [](const json& s) { return s.contains("toi_late"); });
  rows.push_back({"scene", "triangles", "steps", "strategy", "ms/step", "stages (ms)", "vs full", "candidates/step",
                  "tests/step", "colliding", "missed (culled/tested)", "false alarms"});
  if (with_toi) rows.back().push_back("TOI late (error max / mean)");
  for (const json& s : summaries) {
    const std::string strategy = s["strategy"];
    std::string speedup = "-";
    if (!s.value("resumed", false)) {
      // Against the `full` cell of this invocation with the same narrow phase (the token after '+').
      auto narrow_token = [](const std::string& name) {
        const std::size_t plus = name.find('+');
        return plus == std::string::npos ? std::string() : name.substr(plus + 1, name.find(':', plus) - plus - 1);
      };
      const json* full = nullptr;
      for (const json& other : summaries) {
        const std::string name = other["strategy"];
        // A strategy without a narrow phase of ours (fcl) is compared with the first `full` cell.
        const bool same_narrow = narrow_token(strategy).empty() || narrow_token(name) == narrow_token(strategy);
        // Timings compare only on one rank of one machine (MPI spreads cells over ranks and hosts).
        const bool same_place = other.value("rank", 0) == s.value("rank", 0) && other.value("machine", "") == s.value("machine", "");
        if (other["scene"] == s["scene"] && !other.value("resumed", false) && name.rfind("full+", 0) == 0 && same_narrow &&
            same_place && !full) {
          full = &other;
        }
      }
      if (full && s["ms_per_step"].get<double>() > 0) {
        speedup = format((*full)["ms_per_step"].get<double>() / s["ms_per_step"].get<double>(), 2) + "x";
      }
    }
    std::string stages;
    for (const auto& [stage, ms] : s["stage_ms"].items()) stages += (stages.empty() ? "" : ", ") + stage + " " + format(ms.get<double>(), 2);
    const bool verified = s.value("verified", false);
    rows.push_back({s["scene"].get<std::string>() + (s.value("resumed", false) ? " (resumed)" : ""),
                    std::to_string(s["triangles"].get<std::size_t>()), std::to_string(s["steps"].get<std::size_t>()),
                    strategy + (s.value("judged_by", "") == "triangle pairs" ? std::string(kTrianglePairMark) : ""),
                    format(s["ms_per_step"].get<double>(), 3), stages, speedup,
                    format(s["candidate_pairs"].get<double>(), 0), format(s["elementary_tests"].get<double>(), 0),
                    verified ? std::to_string(s["colliding"].get<std::size_t>()) : "-",
                    verified ? std::to_string(s["missed"].get<std::size_t>()) + " (" + std::to_string(s["missed_culled"].get<std::size_t>()) +
                                   "/" + std::to_string(s["missed_tested"].get<std::size_t>()) + ")"
                             : "-",
                    verified ? std::to_string(s["false_alarms"].get<std::size_t>()) : "-"});
    if (with_toi) {
      std::ostringstream toi;
      if (s.contains("toi_late")) {
        toi << s["toi_late"].get<std::size_t>() << " of " << s["toi_checked"].get<std::size_t>() << " (" << std::setprecision(3)
            << s["toi_error_max"].get<double>() << " / " << s["toi_error_mean"].get<double>() << ")";
      } else {
        toi << "-";
      }
      rows.back().push_back(toi.str());
    }
  }
  return rows;
}

void print_table(const std::vector<std::vector<std::string>>& rows, std::ostream& out) {
  std::vector<std::size_t> widths(rows[0].size(), 0);
  for (const auto& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c) widths[c] = std::max(widths[c], row[c].size());
  }
  for (const auto& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c) out << std::left << std::setw(static_cast<int>(widths[c]) + 2) << row[c];
    out << '\n';
  }
  out << table_notes(rows);
}

void write_report(const std::filesystem::path& directory, const std::vector<std::vector<std::string>>& rows,
                  const std::vector<json>& cells, const std::string& command) {
  json steps = json::array();
  for (const json& cell : cells) {
    for (const json& step : cell["steps"]) steps.push_back(step);
  }
  write_json_file(directory / "steps.json", steps);
  datasets::AtomicFile file(directory / "README.md", std::ios::out);
  std::ostream& out = file.stream();
  out << "# ccdbench run\n\nEvery number below comes from one invocation (speed-ups only between cells of this run):\n\n```sh\n"
      << command << "\n```\n\n";
  out << "|";
  for (const auto& h : rows[0]) out << ' ' << h << " |";
  out << "\n|";
  for (std::size_t c = 0; c < rows[0].size(); ++c) out << "---|";
  out << '\n';
  for (std::size_t r = 1; r < rows.size(); ++r) {
    out << "|";
    for (const auto& cell : rows[r]) out << ' ' << cell << " |";
    out << '\n';
  }
  out << '\n' << table_notes(rows);
  const json env = environment();
  out << "\nMachine: " << env["machine"].get<std::string>() << "; build " << env["build_type"].get<std::string>()
      << ", " << env["threads"] << " threads, revision " << env["git_revision"].get<std::string>() << ".\n\n"
      << "![ms per step over the steps](ms_per_step.png)\n\n![stage breakdown per strategy](stages.png)\n\n"
      << "Plots drawn by `scripts/plot_run.py` from `steps.json`.\n";
  file.commit();
}

}  // namespace

std::string scene_file_label(const std::filesystem::path& path) {
  std::filesystem::path normal = path.lexically_normal();
  if (!normal.has_filename()) normal = normal.parent_path();  // "g1/" -> "g1"
  if (normal.filename() == "scene.json") normal = normal.parent_path();
  const std::string name = normal.filename().string();
  return name.empty() || name == "." || name == ".." ? std::filesystem::absolute(normal).lexically_normal().filename().string() : name;
}

std::vector<std::string> suite_names() { return {"ci", "default", "paper"}; }

std::vector<SceneSource> suite_scenes(const std::string& suite) {
  if (suite == "ci") {
    // Every cell the gate holds (scene x strategy x δ) must have colliding pairs, at the scenes' δ and at δ = 0, or
    // it gates nothing. The simulator keeps cloth about δ/2 off everything, so its scenes rarely touch at δ = 0:
    // spinning-ball does (cloth against the ball's mesh), and the kinematic fold makes real crossings of the sheet
    // with itself and with a blade, found by apccd inside its sessions as well as at their starts. The fold with
    // obstacles=shape drives a box (the blade) and a sphere through the sheet: face-shape contacts at δ = 0 too.
    return {generated("spinning-ball", {{"resolution", 8}, {"frames", 5}}),
            generated("fold", {{"resolution", 8}, {"frames", 24}}),
            generated("fold", {{"resolution", 8}, {"frames", 24}, {"obstacles", 1}})};
  }
  if (suite == "default") {
    std::vector<SceneSource> scenes;
    for (const char* name : {"spinning-ball", "drape", "flag", "twist", "funnel", "pile"}) {
      scenes.push_back(generated(name, {{"resolution", 16}, {"frames", 20}}));
    }
    return scenes;
  }
  if (suite == "paper") {
    return {generated("spinning-ball", {{"resolution", 100}, {"frames", 100}}),
            generated("drape", {{"resolution", 100}, {"frames", 100}}),
            generated("flag", {{"resolution", 100}, {"frames", 100}}),
            generated("twist", {{"resolution", 80}, {"frames", 100}}),
            generated("funnel", {{"resolution", 100}, {"frames", 100}}),
            generated("pile", {{"resolution", 64}, {"frames", 100}})};
  }
  throw std::invalid_argument("unknown suite '" + suite + "' (known: ci, default, paper)");
}

namespace {

/// The scenes this rank has loaded, by index in RunOptions::scenes: loaded when a work item first needs one, and
/// at most kKept at once (a rank may alternate between scenes when the work queue hands out cells of several).
class SceneStore {
 public:
  explicit SceneStore(const RunOptions& options) : options_(options) {}

  SceneData& get(std::size_t index) {
    for (auto it = loaded_.begin(); it != loaded_.end(); ++it) {
      if (it->first != index) continue;
      loaded_.splice(loaded_.begin(), loaded_, it);
      return *loaded_.front().second;
    }
    const SceneSource& source = options_.scenes.at(index);
    auto data = std::make_unique<SceneData>(SceneData{source.label, source.load(), {}, {}, {}, 0});
    if (options_.thickness) data->sequence.set_thickness(*options_.thickness);
    data->steps = data->sequence.num_steps();
    if (options_.max_steps > 0) data->steps = std::min(data->steps, options_.max_steps);
    if (data->steps == 0) throw InputError(source.label, {}, "the scene has no steps (one frame)");
    for (std::size_t k = 0; k <= data->steps; ++k) data->frames.push_back(data->sequence.frame(k));
    data->truth.resize(data->steps);
    data->has_truth.assign(data->steps, false);
    loaded_.emplace_front(index, std::move(data));
    if (loaded_.size() > kKept) loaded_.pop_back();
    return *loaded_.front().second;
  }

 private:
  static constexpr std::size_t kKept = 2;
  const RunOptions& options_;
  std::list<std::pair<std::size_t, std::unique_ptr<SceneData>>> loaded_;
};

/// What rank 0 knows of a work item beside its payload: for whom it prints progress and where a cell goes.
struct PlannedItem {
  std::string label;
  std::size_t step = 0, steps = 0;
  bool cell = false;
  std::size_t slot = 0;  // the cell's place in the output
  std::filesystem::path file;
  CellKey key;
};

std::string on_rank(int rank) {
  return rank_info().size > 1 ? " (rank " + std::to_string(rank) + ")" : std::string();
}

}  // namespace

std::vector<json> run_benchmark(const RunOptions& options, std::ostream& out) {
  for (const std::string& spec : options.strategies) strategies::make_strategy(spec);  // unknown names fail first
  const bool planner = rank_info().rank == 0;
  if (planner) {
    // Every output is checked before any work: a run must not compute for an hour and then fail to write.
    datasets::require_writable_directory(options.out);
    datasets::require_writable_directory(options.out / "cells");
    if (options.json) datasets::require_writable_file(*options.json);
    if (options.report) datasets::require_writable_directory(*options.report);
    if (options.misses) datasets::require_writable_directory(*options.misses);
  }
  const TruthCache truth_cache(datasets::procedural_cache_root() / "truth");
  SceneStore store(options);
  std::size_t cells_finished_here = 0;

  // Work items (harness/work_queue.hpp): {"truth", scene, step} computes or reads one step's truth into the cache
  // (and this rank's memory); {"cell", scene, spec, file} runs a cell. Steps of a cell are never split: strategies
  // keep state from step to step.
  const WorkFunction work = [&](const std::string& payload) -> std::string {
    const json task = json::parse(payload);
    // A cell's key (and file name, chosen by rank 0) holds rank 0's thread count: a rank with another would write
    // cells that no rerun can find.
    if (task.at("threads").get<std::size_t>() != worker_threads()) {
      throw std::invalid_argument("rank " + std::to_string(rank_info().rank) + " has " + std::to_string(worker_threads()) +
                                  " worker threads and rank 0 " + task.at("threads").dump() +
                                  ": give --threads so that every rank has the same (timings, and so cell keys, depend on it)");
    }
    SceneData& data = store.get(task.at("scene").get<std::size_t>());
    const Scene& scene = data.sequence.scene();
    auto load_truth = [&](std::size_t k) {
      bool computed = false;
      data.truth[k] = truth_cache.truth(scene, data.frames[k], data.frames[k + 1], computed, options.toi);
      data.has_truth[k] = true;
      return computed;
    };
    if (task.at("kind") == "truth") {
      const std::size_t k = task.at("step");
      const bool computed = load_truth(k);
      return json{{"computed", computed}}.dump();
    }
    if (rank_info().rank != 0) test_hook_rank_exit(cells_finished_here);
    if (options.verify) {
      // Truth steps computed on other ranks are in the cache by now (they finished before this cell was handed out).
      for (std::size_t k = 0; k < data.steps; ++k) {
        if (!data.has_truth[k]) load_truth(k);
      }
    }
    json result = run_cell(data, task.at("spec"), options, data.steps, task.at("file"));
    ++cells_finished_here;
    return result.dump();
  };
  if (!planner) {
    distribute({}, work, {});
    return {};
  }

  std::vector<std::optional<json>> cells;
  std::vector<WorkItem> items;
  std::vector<PlannedItem> planned;
  // Plans scene s: its kept cells go into `cells`, its truth steps and pending cells become work items.
  auto plan_scene = [&](std::size_t s) {
    const SceneSource& source = options.scenes[s];
    std::cerr << "run: loading " << source.label << "\n";
    const SceneData& data = store.get(s);
    const std::size_t steps = data.steps;
    const Scene& scene = data.sequence.scene();
    const std::string content = scene_content_digest(scene, data.frames);
    struct Pending {
      std::string spec;
      std::filesystem::path file;
      CellKey key;
      std::size_t slot;  // cells keep the order of --strategy, kept or computed
    };
    std::vector<Pending> pending;
    for (const std::string& spec : options.strategies) {
      CellKey key{source.label, content, steps, scene.thickness(), options.thickness ? "command line" : "scene",
                  strategies::make_strategy(spec)->name(), options.verify, options.toi, options.repeats,
                  worker_threads(), executable_digest()};
      const auto file = options.out / "cells" / cell_file_name(key);
      std::optional<json> kept;
      if (!options.fresh) {
        try {
          kept = read_cell(file, key);
        } catch (const InputError& corrupt) {
          throw InputError(corrupt.file(), corrupt.where(), corrupt.reason() + " (remove the file, or rerun with --fresh)");
        }
      }
      if (kept) {
        (*kept)["summary"]["resumed"] = true;
        std::cerr << "run: " << source.label << " / " << key.strategy << ": kept from an earlier run with the same inputs, "
                  << "strategy, steps, δ, repeats, threads and executable (--fresh reruns it)"
                  << (options.misses ? "; its misses are not written to --misses again" : "") << "\n";
        cells.push_back(std::move(*kept));
      } else {
        pending.push_back({spec, file, std::move(key), cells.size()});
        cells.emplace_back();
      }
    }
    if (pending.empty()) return;
    // A strategy that refuses this scene (fcl at δ > 0) says so before any truth or timing is spent.
    for (const Pending& cell : pending) strategies::make_strategy(cell.spec)->check_scene(scene);
    std::vector<std::size_t> truth_items;
    if (options.verify) {
      for (std::size_t k = 0; k < steps; ++k) {
        truth_items.push_back(items.size());
        items.push_back({json{{"kind", "truth"}, {"scene", s}, {"step", k}, {"threads", worker_threads()}}.dump(), {}});
        planned.push_back({source.label, k, steps, false, 0, {}, {}});
      }
    }
    for (Pending& cell : pending) {
      const std::string file = cell.file.filename().string();
      items.push_back({json{{"kind", "cell"}, {"scene", s}, {"spec", cell.spec}, {"file", file}, {"threads", worker_threads()}}.dump(),
                       truth_items});
      planned.push_back({source.label, 0, steps, true, cell.slot, std::move(cell.file), std::move(cell.key)});
    }
  };
  std::size_t cell_count = 0, cells_done = 0;
  const DoneFunction done = [&](std::size_t index, const std::string& text, int rank) {
    PlannedItem& item = planned.at(index);
    json result = json::parse(text);
    if (!item.cell) {
      std::cerr << "run: " << item.label << ": truth of step " << item.step + 1 << "/" << item.steps
                << (result.at("computed").get<bool>() ? " computed" : " cached") << on_rank(rank) << "\n";
      return;
    }
    result["key"] = item.key.to_json();
    result["summary"]["key"] = result["key"];
    write_cell(item.file, result);
    rebuild_results_log(options.out, std::cerr);
    ++cells_done;
    test_hook_rank_exit(cells_done);
    if (rank_info().size > 1) {
      std::cerr << "run: " << item.label << " / " << item.key.strategy << ": cell " << cells_done << " of " << cell_count
                << " done" << on_rank(rank) << "\n";
    }
    cells[item.slot] = std::move(result);
  };
  if (rank_info().size == 1) {
    // One process: scene by scene, as before MPI (each scene loaded once, when its turn comes).
    for (std::size_t s = 0; s < options.scenes.size(); ++s) {
      items.clear();
      planned.clear();
      plan_scene(s);
      distribute(items, work, done);
    }
  } else {
    for (std::size_t s = 0; s < options.scenes.size(); ++s) plan_scene(s);
    cell_count = static_cast<std::size_t>(std::count_if(planned.begin(), planned.end(), [](const PlannedItem& p) { return p.cell; }));
    say_on_termination("run: stopped before every cell finished (a rank died, or the run was interrupted): finished "
                       "cells are kept in " + (options.out / "cells").string() +
                       "; the same command again, with any number of ranks, runs only the rest\n");
    distribute(items, work, done);
    say_on_termination({});
  }

  std::vector<json> summaries;
  for (const std::optional<json>& cell : cells) summaries.push_back(cell->at("summary"));
  const auto rows = table_rows(summaries);
  print_table(rows, out);
  if (options.json) write_json_file(*options.json, summaries);
  if (options.report) {
    std::vector<json> finished;
    for (const std::optional<json>& cell : cells) finished.push_back(*cell);
    write_report(*options.report, rows, finished, options.command_line);
    out << "report: " << (*options.report / "README.md").string() << "\n";
  }
  out << "results: " << (options.out / "results.jsonl").string() << " (every finished cell of every run into "
      << options.out.string() << ")\n";
  return summaries;
}

namespace {

/// A gated cell's identity: (scene, strategy, δ). δ is "scene" (the scene's own) or the number the cell ran at.
struct GateKey {
  std::string scene, strategy;
  std::optional<double> thickness;  // nullopt: the scene's own

  std::string describe() const {
    std::ostringstream text;
    text << scene << " / " << strategy << " / δ " << (thickness ? "" : "scene's");
    if (thickness) text << std::setprecision(17) << *thickness;
    return text.str();
  }
};

struct BaselineEntry {
  GateKey key;
  std::uint64_t max_missed = 0;
  /// Optional pins: the cell must have exactly these steps and colliding pairs (a shorter run or a shrunken truth
  /// must not pass), and at most max_toi_late late TOIs (the results must then come from a run with --toi).
  std::optional<std::uint64_t> steps, colliding, max_toi_late;
};

std::vector<BaselineEntry> parse_baseline(const json& baseline, const std::filesystem::path& file) {
  if (!baseline.is_array()) throw InputError(file, {}, "a baseline is a JSON array of {scene, strategy, thickness, max_missed}");
  std::vector<BaselineEntry> entries;
  for (std::size_t i = 0; i < baseline.size(); ++i) {
    const json& entry = baseline[i];
    const std::string where = "entry " + std::to_string(i);
    if (!entry.is_object()) throw InputError(file, where, "must be an object");
    static const std::vector<std::string> kKeys = {"scene", "strategy", "thickness", "max_missed", "steps", "colliding", "max_toi_late"};
    for (const auto& item : entry.items()) {
      if (std::find(kKeys.begin(), kKeys.end(), item.key()) == kKeys.end()) {
        throw InputError(file, where, "unknown key '" + item.key() +
                                          "' (allowed: scene, strategy, thickness, max_missed, steps, colliding, max_toi_late)");
      }
    }
    BaselineEntry parsed;
    if (!entry.contains("scene") || !entry["scene"].is_string()) throw InputError(file, where + ".scene", "must be a string");
    if (!entry.contains("strategy") || !entry["strategy"].is_string()) throw InputError(file, where + ".strategy", "must be a string");
    parsed.key.scene = entry["scene"];
    parsed.key.strategy = entry["strategy"];
    if (!entry.contains("thickness")) throw InputError(file, where, "missing 'thickness': \"scene\" (the scene's own δ) or a number");
    const json& thickness = entry["thickness"];
    if (thickness.is_string() && thickness == "scene") {
      parsed.key.thickness = std::nullopt;
    } else if (thickness.is_number() && std::isfinite(thickness.get<double>()) && thickness.get<double>() >= 0) {
      parsed.key.thickness = thickness.get<double>();
    } else {
      throw InputError(file, where + ".thickness", "must be \"scene\" or a finite number >= 0");
    }
    if (!entry.contains("max_missed") || !entry["max_missed"].is_number_unsigned()) {
      throw InputError(file, where + ".max_missed", "must be an integer >= 0, got " + (entry.contains("max_missed") ? entry["max_missed"].dump() : std::string("nothing")));
    }
    parsed.max_missed = entry["max_missed"].get<std::uint64_t>();
    for (auto [name, field] : {std::pair{"steps", &parsed.steps}, {"colliding", &parsed.colliding}, {"max_toi_late", &parsed.max_toi_late}}) {
      if (!entry.contains(name)) continue;
      if (!entry[name].is_number_unsigned()) throw InputError(file, where + "." + name, "must be an integer >= 0");
      *field = entry[name].get<std::uint64_t>();
    }
    for (const BaselineEntry& other : entries) {
      if (other.key.scene == parsed.key.scene && other.key.strategy == parsed.key.strategy && other.key.thickness == parsed.key.thickness) {
        throw InputError(file, where, "repeats the entry for " + parsed.key.describe());
      }
    }
    entries.push_back(std::move(parsed));
  }
  return entries;
}

std::uint64_t result_count(const json& result, const char* field, const std::filesystem::path& file, const std::string& where) {
  if (!result.contains(field) || !result[field].is_number_unsigned()) {
    throw InputError(file, where + "." + field, "must be an integer >= 0 (a `ccdbench run --json` summary, verified)");
  }
  return result[field].get<std::uint64_t>();
}

}  // namespace

bool check_against_baseline(const json& baseline, const std::filesystem::path& baseline_file,
                            const std::vector<std::pair<std::filesystem::path, json>>& results_files, std::ostream& out) {
  const std::vector<BaselineEntry> entries = parse_baseline(baseline, baseline_file);
  std::vector<std::tuple<std::filesystem::path, std::size_t, const json*>> results;
  for (const auto& [file, document] : results_files) {
    if (!document.is_array()) throw InputError(file, {}, "must be a JSON array (a `ccdbench run --json` file)");
    for (std::size_t i = 0; i < document.size(); ++i) results.emplace_back(file, i, &document[i]);
  }
  bool ok = true;
  if (results.empty()) {
    out << "FAIL the results are empty: nothing was gated\n";
    ok = false;
  }
  std::vector<std::size_t> matches(entries.size(), 0);
  for (const auto& [results_file, i, result_pointer] : results) {
    const json& result = *result_pointer;
    const std::string where = "entry " + std::to_string(i);
    if (!result.is_object() || !result.contains("scene") || !result["scene"].is_string() || !result.contains("strategy") ||
        !result["strategy"].is_string() || !result.contains("thickness") || !result["thickness"].is_number() ||
        !result.contains("thickness_from") || !result["thickness_from"].is_string()) {
      throw InputError(results_file, where, "not a summary of `ccdbench run --json` (scene, strategy, thickness, thickness_from)");
    }
    const GateKey key{result["scene"], result["strategy"], result["thickness"].get<double>()};
    const bool scene_thickness = result["thickness_from"] == "scene";
    const BaselineEntry* entry = nullptr;
    std::size_t entries_matched = 0;
    for (std::size_t e = 0; e < entries.size(); ++e) {
      const GateKey& gate = entries[e].key;
      const bool same_thickness = gate.thickness ? *gate.thickness == *key.thickness : scene_thickness;
      if (gate.scene == key.scene && gate.strategy == key.strategy && same_thickness) {
        entry = &entries[e];
        ++matches[e];
        ++entries_matched;
      }
    }
    const std::string name = key.scene + " / " + key.strategy + " / δ " + (scene_thickness ? "scene's " : "") +
                             [&] { std::ostringstream t; t << std::setprecision(17) << *key.thickness; return t.str(); }();
    if (!entry) {
      out << "FAIL " << name << ": not in the baseline (every gated cell needs an entry)\n";
      ok = false;
      continue;
    }
    if (entries_matched > 1) {
      // The scene's own δ equals a numeric entry's: which entry gates it would be an accident of order.
      out << "FAIL " << name << ": matches " << entries_matched << " baseline entries (make them distinct)\n";
      ok = false;
      continue;
    }
    if (!result.value("verified", false) || !result.contains("missed")) {
      out << "FAIL " << name << ": not verified (run with --verify exact)\n";
      ok = false;
      continue;
    }
    const std::uint64_t missed = result_count(result, "missed", results_file, where);
    const std::uint64_t colliding = result_count(result, "colliding", results_file, where);
    if (entry->steps && result_count(result, "steps", results_file, where) != *entry->steps) {
      out << "FAIL " << name << ": " << result["steps"].dump() << " steps, the baseline pins " << *entry->steps << "\n";
      ok = false;
    } else if (entry->colliding && colliding != *entry->colliding) {
      out << "FAIL " << name << ": " << colliding << " colliding pairs, the baseline pins " << *entry->colliding
          << " (the scene or the truth changed: check why before updating the baseline)\n";
      ok = false;
    } else if (entry->max_toi_late && !result.contains("toi_late")) {
      out << "FAIL " << name << ": the baseline gates late TOIs but the results have none (run with --toi)\n";
      ok = false;
    } else if (entry->max_toi_late && result_count(result, "toi_late", results_file, where) > *entry->max_toi_late) {
      out << "FAIL " << name << ": " << result["toi_late"].dump() << " TOIs later than the exact earliest contact, "
          << "baseline allows " << *entry->max_toi_late << "\n";
      ok = false;
    } else if (colliding == 0) {
      out << "FAIL " << name << ": no colliding pair in any step, so it cannot miss: this cell gates nothing\n";
      ok = false;
    } else if (missed > entry->max_missed) {
      out << "FAIL " << name << ": missed " << missed << " of " << colliding << " (culled "
          << result.value("missed_culled", json(0)).dump() << ", tested " << result.value("missed_tested", json(0)).dump()
          << "), baseline allows " << entry->max_missed << "\n";
      ok = false;
    } else {
      out << "ok   " << name << ": missed " << missed << " of " << colliding << " <= " << entry->max_missed << "\n";
    }
  }
  for (std::size_t e = 0; e < entries.size(); ++e) {
    if (matches[e] == 0) {
      out << "FAIL " << entries[e].key.describe() << ": in the baseline but has no result\n";
      ok = false;
    } else if (matches[e] > 1) {
      out << "FAIL " << entries[e].key.describe() << ": " << matches[e] << " results for one entry\n";
      ok = false;
    }
  }
  return ok;
}

}  // namespace ccd::harness
