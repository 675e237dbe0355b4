#include "harness/run/records.hpp"

#include <stdexcept>

namespace ccd::harness {

using nlohmann::json;

namespace {

template <class T>
std::optional<T> optional_field(const json& j, const char* name) {
  if (!j.contains(name) || j.at(name).is_null()) return std::nullopt;
  return j.at(name).get<T>();
}

template <class T>
void put_optional(json& j, const char* name, const std::optional<T>& value) {
  if (value) j[name] = *value;
}

void put_counts(json& j, const VerdictCounts& v) {
  j["colliding"] = v.colliding;
  j["missed"] = v.missed;
  j["missed_culled"] = v.missed_culled;
  j["missed_tested"] = v.missed_tested;
  j["false_alarms"] = v.false_alarms;
  put_optional(j, "colliding_face_shape", v.colliding_face_shape);
  put_optional(j, "missed_face_shape", v.missed_face_shape);
}

/// A verdict is read where a record has its colliding and missed counts; what else it counts is 0 where absent (a
/// record made by hand, which check and compare take with only the fields they read).
bool has_verdict(const json& j) { return j.contains("colliding") && j.contains("missed"); }

void read_counts(const json& j, VerdictCounts& v) {
  v.colliding = j.at("colliding").get<std::size_t>();
  v.missed = j.at("missed").get<std::size_t>();
  v.missed_culled = j.value("missed_culled", std::size_t{0});
  v.missed_tested = j.value("missed_tested", std::size_t{0});
  v.false_alarms = j.value("false_alarms", std::size_t{0});
  v.colliding_face_shape = optional_field<std::size_t>(j, "colliding_face_shape");
  v.missed_face_shape = optional_field<std::size_t>(j, "missed_face_shape");
}

/// The record's "record" field, where it has one (a summary made by hand for the gate may not), must say what it is.
void expect_kind(const json& j, const char* kind) {
  if (!j.is_object() || j.value("record", std::string(kind)) != kind) {
    throw std::invalid_argument(std::string("not a ") + kind + " record: its \"record\" is not \"" + kind + "\"");
  }
}

/// How the records spell a cell's δ's origin and what a cell is judged by.
constexpr const char* kThicknessFromScene = "scene";
constexpr const char* kThicknessFromCommandLine = "command line";
constexpr const char* kJudgedByTrianglePairs = "triangle pairs";
constexpr const char* kJudgedByElementaryPairs = "elementary pairs";

/// The TOI verdict is read where a record has its late count (the one the gate and compare judge).
bool has_toi(const json& j) { return j.contains("toi_late"); }

}  // namespace

void to_json(json& j, const MissedPair& p) { j = {{"kind", p.kind()}, {"ids", p.ids}, {"rows", p.rows}}; }

void from_json(const json& j, MissedPair& p) {
  const std::string kind = j.at("kind").get<std::string>();
  if (kind != "vf" && kind != "ee") throw std::invalid_argument("a missed pair's kind is \"vf\" or \"ee\", not \"" + kind + "\"");
  p.vertex_face = kind == "vf";
  p.ids = j.at("ids").get<std::vector<std::size_t>>();
  p.rows = j.at("rows").get<std::array<double, 24>>();
}

VerdictCounts& VerdictCounts::operator+=(const VerdictCounts& other) {
  colliding += other.colliding;
  missed += other.missed;
  missed_culled += other.missed_culled;
  missed_tested += other.missed_tested;
  false_alarms += other.false_alarms;
  for (auto [total, add] : {std::pair{&colliding_face_shape, &other.colliding_face_shape}, std::pair{&missed_face_shape, &other.missed_face_shape}}) {
    if (*add) *total = total->value_or(0) + **add;
  }
  return *this;
}

void to_json(json& j, const RecordEnvironment& e) {
  j = {{"machine", e.machine},
       {"build_type", e.build_type},
       {"git_revision", e.git_revision},
       {"executable", e.executable},
       {"provenance", e.provenance},
       {"threads", e.threads},
       {"rank", e.rank}};
}

void from_json(const json& j, RecordEnvironment& e) {
  e.machine = j.value("machine", std::string());
  e.build_type = j.value("build_type", std::string());
  e.git_revision = j.value("git_revision", std::string());
  e.executable = j.value("executable", std::string());
  e.provenance = j.value("provenance", json::object());
  e.threads = j.value("threads", std::size_t{0});
  e.rank = j.value("rank", 0);
}

void to_json(json& j, const StepRecord& r) {
  j = {{"record", "step"},
       {"schema", r.schema},
       {"scene", r.scene},
       {"thickness", r.thickness},
       {"strategy", r.strategy},
       {"step", r.step},
       {"ms", r.ms},
       {"ms_repeats", r.ms_repeats},
       {"stages", r.stages},
       {"candidate_pairs", r.candidate_pairs},
       {"elementary_tests", r.elementary_tests},
       {"kept_bytes", r.kept_bytes},
       {"history_bytes", r.history_bytes},
       {"device_bytes", r.device_bytes},
       {"reported", r.reported}};
  put_optional(j, "answers", r.answers);
  if (r.errors > 0) {
    j["errors"] = r.errors;
    j["error_first"] = r.error_first;
  }
  for (const auto& [name, value] : r.counters) j[name] = value;
  if (const std::optional<StepVerdict>& v = r.verdict) {
    put_counts(j, *v);
    put_optional(j, "missed_pairs", v->missed_pairs);
    if (v->toi) {
      j["toi_checked"] = v->toi->checked;
      j["toi_late"] = v->toi->late;
      j["toi_error_max"] = v->toi->error_max;
    }
  }
  j.update(json(r.environment));
}

namespace {

/// A step record's own fields, its environment's included, as the serializer writes them with every optional part
/// present: every other field of a step record is a counter of its strategy. Derived from the serializer, so a field
/// added there is known here at once.
const json& step_fields() {
  static const json fields = [] {
    StepRecord every;
    every.answers = std::string();
    every.errors = 1;
    StepVerdict verdict;
    verdict.colliding_face_shape = verdict.missed_face_shape = 0;
    verdict.missed_pairs = std::vector<MissedPair>();
    verdict.toi.emplace();
    every.verdict = verdict;
    return json(every);
  }();
  return fields;
}

}  // namespace

void from_json(const json& j, StepRecord& r) {
  expect_kind(j, "step");
  r.schema = j.value("schema", 1);
  r.scene = j.at("scene").get<std::string>();
  r.thickness = j.at("thickness").get<double>();
  r.strategy = j.at("strategy").get<std::string>();
  r.step = j.at("step").get<std::size_t>();
  r.ms = j.value("ms", 0.0);
  r.ms_repeats = j.value("ms_repeats", std::vector<double>{});
  r.stages = j.value("stages", std::map<std::string, double>{});
  r.candidate_pairs = j.value("candidate_pairs", std::size_t{0});
  r.elementary_tests = j.value("elementary_tests", std::size_t{0});
  r.kept_bytes = j.value("kept_bytes", std::size_t{0});
  r.history_bytes = j.value("history_bytes", std::size_t{0});
  r.device_bytes = j.value("device_bytes", std::size_t{0});
  r.reported = j.value("reported", std::size_t{0});
  r.answers = optional_field<std::string>(j, "answers");
  r.errors = j.value("errors", std::size_t{0});
  r.error_first = j.value("error_first", std::string());
  r.counters.clear();
  for (const auto& [name, value] : j.items()) {
    if (step_fields().contains(name)) continue;
    if (!value.is_number()) throw std::invalid_argument("step record: field \"" + name + "\" is neither a known field nor a counter (a number)");
    r.counters.emplace_back(name, value.get<double>());
  }
  r.verdict.reset();
  if (has_verdict(j)) {
    StepVerdict v;
    read_counts(j, v);
    if (j.contains("missed_pairs")) v.missed_pairs = j.at("missed_pairs").get<std::vector<MissedPair>>();
    if (has_toi(j)) {
      v.toi.emplace();
      v.toi->checked = j.value("toi_checked", std::size_t{0});
      v.toi->late = j.value("toi_late", std::size_t{0});
      v.toi->error_max = j.value("toi_error_max", 0.0);
    }
    r.verdict = std::move(v);
  }
  r.environment = j.get<RecordEnvironment>();
}

void to_json(json& j, const CellSummary& s) {
  json counters = json::object();
  for (const auto& [name, counter] : s.counters) counters[name] = {{"mean", counter.mean}, {"max", counter.max}};
  j = {{"record", "summary"},
       {"schema", s.schema},
       {"scene", s.scene},
       {"strategy", s.strategy},
       {"spec", s.spec},
       {"triangles", s.triangles},
       {"vertices", s.vertices},
       {"steps", s.steps},
       {"thickness", s.thickness},
       {"ms_per_step", s.ms_per_step},
       {"ms_per_step_mean", s.ms_per_step_mean},
       {"ms_per_repeat", s.ms_per_repeat},
       {"stage_ms", s.stage_ms},
       {"stage_ms_mean", s.stage_ms_mean},
       {"unattributed_ms_mean", s.unattributed_ms_mean},
       {"setup_ms", s.setup_ms},
       {"counters", counters},
       {"candidate_pairs", s.candidate_pairs},
       {"elementary_tests", s.elementary_tests},
       {"kept_bytes", s.kept_bytes},
       {"history_bytes", s.history_bytes},
       {"device_bytes", s.device_bytes},
       {"host_peak_bytes", s.host_peak_bytes},
       {"host_peak_of", s.host_peak_of},
       {"reported", s.reported},
       {"judged_by", s.judged_by == strategies::Judging::triangle_pairs ? kJudgedByTrianglePairs : kJudgedByElementaryPairs},
       {"thickness_from", s.thickness_from_scene ? kThicknessFromScene : kThicknessFromCommandLine},
       {"verified", s.verified},
       {"repeats", s.repeats},
       {"cell", s.cell},
       {"finished_at", s.finished_at}};
  // A summary read back without its errors counted is written so again: never as 0 errors.
  if (s.errors_counted) j["errors"] = s.errors;
  if (const std::optional<CellVerdict>& v = s.verdict) {
    put_counts(j, *v);
    j.update(json{{"miss_causes", v->miss_causes},
                  {"colliding_by_objects", v->colliding_by_objects},
                  {"faces_in_contact_by_objects", v->faces_in_contact_by_objects}});
    if (const std::optional<CellVerdict::Toi>& toi = v->toi) {
      j.update(json{{"toi_checked", toi->checked},
                    {"toi_late", toi->late},
                    {"toi_missing", toi->missing},
                    {"toi_error_max", toi->error_max},
                    {"toi_error_mean", toi->error_mean},
                    {"toi_error_median", toi->error_median ? json(*toi->error_median) : json()},
                    {"toi_error_p99", toi->error_p99 ? json(*toi->error_p99) : json()}});
    }
  }
  if (s.child_peak_bytes > 0) j["child_peak_bytes"] = s.child_peak_bytes;
  put_optional(j, "errors_written", s.errors_written);
  put_optional(j, "nondeterministic_at_step", s.nondeterministic_at_step);
  put_optional(j, "interleave_group", s.interleave_group);
  j.update(json(s.environment));
  put_optional(j, "key", s.key);
  if (s.resumed) j["resumed"] = true;
  if (s.speedup) {
    j["speedup"] = s.speedup->ratio ? json(*s.speedup->ratio) : json();
    j["speedup_over"] = s.speedup->over ? json(*s.speedup->over) : json();
  }
}

void from_json(const json& j, CellSummary& s) {
  expect_kind(j, "summary");
  s.schema = j.value("schema", 1);
  s.scene = j.at("scene").get<std::string>();
  s.strategy = j.at("strategy").get<std::string>();
  s.spec = j.value("spec", std::string());
  s.triangles = j.value("triangles", std::size_t{0});
  s.vertices = j.value("vertices", std::size_t{0});
  s.steps = j.value("steps", std::size_t{0});
  s.thickness = j.at("thickness").get<double>();
  s.thickness_from_scene = j.value("thickness_from", std::string(kThicknessFromScene)) == kThicknessFromScene;
  s.ms_per_step = j.value("ms_per_step", 0.0);
  s.ms_per_step_mean = j.value("ms_per_step_mean", s.ms_per_step);
  s.unattributed_ms_mean = j.value("unattributed_ms_mean", 0.0);
  s.setup_ms = j.value("setup_ms", 0.0);
  s.ms_per_repeat = j.value("ms_per_repeat", std::vector<double>{});
  s.stage_ms = j.value("stage_ms", std::map<std::string, double>{});
  s.stage_ms_mean = j.value("stage_ms_mean", std::map<std::string, double>{});
  s.counters.clear();
  const json counters = j.value("counters", json::object());
  for (const auto& [name, counter] : counters.items()) {
    s.counters[name] = {counter.at("mean").get<double>(), counter.at("max").get<double>()};
  }
  s.candidate_pairs = j.value("candidate_pairs", 0.0);
  s.elementary_tests = j.value("elementary_tests", 0.0);
  s.kept_bytes = j.value("kept_bytes", 0.0);
  s.history_bytes = j.value("history_bytes", 0.0);
  s.device_bytes = j.value("device_bytes", 0.0);
  s.host_peak_bytes = j.value("host_peak_bytes", 0.0);
  s.host_peak_of = j.value("host_peak_of", std::string("process"));
  s.child_peak_bytes = j.value("child_peak_bytes", 0.0);
  s.reported = j.value("reported", std::size_t{0});
  s.judged_by = j.value("judged_by", std::string(kJudgedByElementaryPairs)) == kJudgedByTrianglePairs ? strategies::Judging::triangle_pairs
                                                                                                      : strategies::Judging::elementary_pairs;
  s.verified = j.value("verified", false);
  s.repeats = j.value("repeats", 1);
  s.cell = j.value("cell", std::string());
  s.errors = j.value("errors", std::size_t{0});
  s.errors_counted = j.contains("errors");
  s.errors_written = optional_field<std::string>(j, "errors_written");
  s.nondeterministic_at_step = optional_field<std::size_t>(j, "nondeterministic_at_step");
  s.interleave_group = optional_field<std::string>(j, "interleave_group");
  s.finished_at = j.value("finished_at", std::string());
  s.verdict.reset();
  if (has_verdict(j)) {
    CellVerdict v;
    read_counts(j, v);
    v.miss_causes = j.value("miss_causes", json::object());
    v.colliding_by_objects = j.value("colliding_by_objects", std::map<std::string, std::size_t>{});
    v.faces_in_contact_by_objects = j.value("faces_in_contact_by_objects", std::map<std::string, std::size_t>{});
    if (has_toi(j)) {
      v.toi.emplace();
      v.toi->checked = j.value("toi_checked", std::size_t{0});
      v.toi->late = j.value("toi_late", std::size_t{0});
      v.toi->missing = j.value("toi_missing", std::size_t{0});
      v.toi->error_max = optional_field<double>(j, "toi_error_max").value_or(0.0);
      v.toi->error_mean = optional_field<double>(j, "toi_error_mean").value_or(0.0);
      v.toi->error_median = optional_field<double>(j, "toi_error_median");
      v.toi->error_p99 = optional_field<double>(j, "toi_error_p99");
    }
    s.verdict = std::move(v);
  }
  s.environment = j.get<RecordEnvironment>();
  if (j.contains("key")) s.key = j.at("key");
  s.resumed = j.value("resumed", false);
  s.speedup.reset();
  if (j.contains("speedup")) {
    s.speedup.emplace();
    s.speedup->ratio = optional_field<double>(j, "speedup");
    s.speedup->over = optional_field<std::string>(j, "speedup_over");
  }
}

void to_json(json& j, const CellRecord& c) {
  j = {{"summary", c.summary}, {"steps", c.steps}};
  // A kept cell is found by its key (read_cell): the summary's, written at the top as well.
  put_optional(j, "key", c.summary.key);
}

void from_json(const json& j, CellRecord& c) {
  c.summary = j.at("summary").get<CellSummary>();
  c.steps = j.at("steps").get<std::vector<StepRecord>>();
}

namespace {

std::optional<double> maybe(bool has, double value) { return has ? std::optional<double>(value) : std::nullopt; }
const CellVerdict::Toi* toi_of(const CellSummary& s) { return s.verdict && s.verdict->toi ? &*s.verdict->toi : nullptr; }

}  // namespace

namespace measures {

const Measure missed{"missed", [](const CellSummary& s) { return maybe(s.verdict.has_value(), s.verdict ? double(s.verdict->missed) : 0); }, true};
const Measure errors{"errors", [](const CellSummary& s) { return maybe(s.errors_counted, double(s.errors)); }, true};
const Measure false_alarms{"false_alarms",
                           [](const CellSummary& s) { return maybe(s.verdict.has_value(), s.verdict ? double(s.verdict->false_alarms) : 0); }, true};
const Measure toi_late{"toi_late", [](const CellSummary& s) { return maybe(toi_of(s) != nullptr, toi_of(s) ? double(toi_of(s)->late) : 0); }, true};
const Measure toi_error_median{"toi_error_median", [](const CellSummary& s) { return toi_of(s) ? toi_of(s)->error_median : std::nullopt; }};
const Measure toi_error_p99{"toi_error_p99", [](const CellSummary& s) { return toi_of(s) ? toi_of(s)->error_p99 : std::nullopt; }};
const Measure toi_error_max{"toi_error_max", [](const CellSummary& s) { return maybe(toi_of(s) != nullptr, toi_of(s) ? toi_of(s)->error_max : 0); }};
// 0: not measured (a record without it); a process always has some.
const Measure host_peak_bytes{"host_peak_bytes", [](const CellSummary& s) { return maybe(s.host_peak_bytes > 0, s.host_peak_bytes); }};
const Measure device_bytes{"device_bytes", [](const CellSummary& s) { return std::optional<double>(s.device_bytes); }};
const Measure ms_per_step{"ms_per_step", [](const CellSummary& s) { return std::optional<double>(s.ms_per_step); }};

}  // namespace measures

}  // namespace ccd::harness
