#include "harness/run/cells.hpp"

#include "ccd/config.hpp"

#include "harness/cell_store.hpp"
#include "harness/run/faults.hpp"
#include "harness/run/provenance.hpp"
#include "harness/run/verdict.hpp"
#include "harness/statistics.hpp"
#include "harness/table.hpp"
#include "harness/timed_region.hpp"
#include "strategies/plugin/call_guard.hpp"
#include "strategies/registry.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <map>
#include <numeric>
#include <optional>

namespace ccd::harness {

using nlohmann::json;

namespace {

/// Resets the process's peak resident memory to its current size (Linux: 5 into /proc/self/clear_refs); false
/// where that is not possible, and the peak read after is then the process's since it started.
bool reset_peak_resident() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
  clear.flush();
  return static_cast<bool>(clear);
}

/// The process's peak resident memory (VmHWM of /proc/self/status), in bytes; 0 where it cannot be read.
std::size_t peak_resident_bytes() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmHWM:", 0) == 0) return static_cast<std::size_t>(std::strtoull(line.c_str() + 6, nullptr, 10)) * 1024;
  }
  return 0;
}

/// What a cell runs with: its scene and truth, its strategy as given, the run's options.
struct CellContext {
  const SceneData& data;
  const strategies::StrategySpec& spec;
  const RunOptions& options;
  std::size_t steps;
  const std::string& cell_name;
  const strategies::StrategyEntry& entry;
  /// Code from outside ccdbench may answer differently when asked again: its cell then says so (and `check` fails
  /// it unless its baseline allows it), where a built-in strategy's would be a defect that ends the run.
  bool from_outside;
};

/// What the timed passes of a cell leave: the first pass's answers and their digests, each step's time in every
/// pass, the stages' times, what ran and where.
struct Passes {
  std::vector<strategies::StepResult> first;
  std::vector<std::string> digests;
  std::vector<std::vector<double>> step_ms;
  std::map<std::string, std::vector<double>> stage_ms;
  /// Each timed step's ms less the sum of its own stages, over every pass: the time no stage names (the summary's
  /// ms_per_step_mean and stage_ms_mean are of medians and of means, and their difference is not this).
  double unattributed_sum = 0;
  std::size_t unattributed_count = 0;
  std::string resolved;
  json environment;
  std::optional<std::size_t> nondeterministic_step;
  double host_peak = 0;
  bool peak_of_cell = false;
};

/// Answers of step `k` differed between two `how` (passes, runs): a verdict for code from outside, else a defect.
void not_deterministic(const CellContext& cell, Passes& passes, std::size_t k, const char* how) {
  if (!cell.from_outside) {
    throw std::runtime_error(passes.resolved + " gave different answers on two " + how + " of step " + std::to_string(k) + " of " + cell.data.label +
                             ": the strategy is not deterministic");
  }
  if (!passes.nondeterministic_step || k < *passes.nondeterministic_step) passes.nondeterministic_step = k;
}

/// One timed pass over every step; the first keeps its answers, later ones are compared with them.
void time_pass(const CellContext& cell, Passes& passes, int repeat, const CellProgress& progress, const std::string& planned_name) {
  const Scene& scene = cell.data.sequence.scene();
  auto strategy = strategies::make_strategy(cell.spec);
  passes.resolved = strategy->name();
  if (!planned_name.empty() && passes.resolved != planned_name) {
    // The key this cell would be kept under names other code than the code that would run.
    throw std::runtime_error(cell.data.label + " / " + cell.spec.label + ": it was planned as " + planned_name + " and would run as " +
                             passes.resolved + ": its code or answers changed during the run; the cells finished before are kept");
  }
  for (const auto& [name, value] : strategy->provenance()) passes.environment["provenance"][name] = value;
  strategy->name_scene(cell.data.label);
  strategy->init(scene, cell.data.frames[0]);
  for (std::size_t k = 0; k < cell.steps; ++k) {
    const StepView view{&scene, k, cell.data.frames[k], cell.data.frames[k + 1]};
    plugin::set_activity("cell " + cell.data.label + " / " + cell.spec.label + ", pass " + std::to_string(repeat + 1) + ", step " +
                         std::to_string(k + 1) + " of " + std::to_string(cell.steps));
    std::optional<strategies::StepResult> answered;
    const auto start = std::chrono::steady_clock::now();
    {
      const TimedRegion timed;
      answered = strategy->step(view, false);
    }
    passes.step_ms[k].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    strategies::StepResult result = std::move(*answered);
    passes.unattributed_sum += passes.step_ms[k].back() - result.stages.total_milliseconds();
    ++passes.unattributed_count;
    for (const auto& [stage, ms] : result.stages.entries()) passes.stage_ms[stage].push_back(ms);
    // Every repeat's answers (pairs, TOI bits, and how many could not be given) against the first pass's, step
    // by step: harness work, after the timed call.
    harness_pass("answers digest");
    const std::string digest = answers_digest(result.collisions);
    if (repeat == 0) {
      passes.digests.push_back(digest);
#if CCDBENCH_GUARD_REPEATS
    } else if (digest != passes.digests[k] || result.fault_count != passes.first[k].fault_count) {
      not_deterministic(cell, passes, k, "passes");
#endif
    }
    if (repeat == 0) passes.first.push_back(std::move(result));
    if (progress) progress(repeat, k, passes.resolved);
  }
}

Passes time_passes(const CellContext& cell, const CellProgress& progress, const std::string& planned_name) {
  Passes passes;
  passes.step_ms.resize(cell.steps);
  passes.environment = environment();
  // The host's peak over the cell's timed passes: the strategy's memory and the frames it is given (the truth and
  // verification come after).
  passes.peak_of_cell = reset_peak_resident();
  for (int repeat = 0; repeat < std::max(1, cell.options.repeats); ++repeat) time_pass(cell, passes, repeat, progress, planned_name);
  plugin::set_activity({});
  passes.host_peak = static_cast<double>(peak_resident_bytes());
  return passes;
}

/// Every step's verdict, and why each miss was missed.
struct Judgement {
  std::vector<Verdict> verdicts;
  json miss_causes = json::object();
};

/// Audit pass, outside every timed region: which misses were never tested (culled) and which tested wrong. A cell
/// whose answers change meanwhile has its misses left unexplained.
void audit(const CellContext& cell, Passes& passes, Judgement& judgement) {
  const Scene& scene = cell.data.sequence.scene();
  const strategies::Judging judging = cell.entry.judging;
  std::vector<strategies::TestedPairs> audited;
  auto strategy = strategies::make_strategy(cell.spec);
  strategy->name_scene(cell.data.label);
  strategy->init(scene, cell.data.frames[0]);
  for (std::size_t k = 0; k < cell.steps && !passes.nondeterministic_step; ++k) {
    plugin::set_activity("cell " + cell.data.label + " / " + cell.spec.label + ", its audit pass, step " + std::to_string(k + 1));
    strategies::StepResult audit = strategy->step({&scene, k, cell.data.frames[k], cell.data.frames[k + 1]}, true);
#if CCDBENCH_GUARD_REPEATS
    // The audit pass is one more run of the same steps: its answers are compared as a timed pass's are.
    if (answers_digest(audit.collisions) != passes.digests[k] || audit.fault_count != passes.first[k].fault_count) {
      not_deterministic(cell, passes, k, "runs");
      break;
    }
#endif
    // A strategy that tests no pair ccdbench sees (a whole-step plugin, answer files) has no audit: its misses
    // are explained by its entry (explain_miss).
    judgement.verdicts[k] = judge(scene, cell.data.truth[k], passes.first[k], judging, audit.tested ? &*audit.tested : nullptr, cell.options.toi);
    audited.push_back(audit.tested ? std::move(*audit.tested) : strategies::TestedPairs{});
  }
  if (!passes.nondeterministic_step) {
    std::optional<std::filesystem::path> directory;
    if (cell.options.misses) directory = *cell.options.misses / safe_path_component(cell.data.label) / std::filesystem::path(cell.cell_name).stem();
    judgement.miss_causes = record_misses(scene, cell.data.frames, cell.data.truth, passes.first, audited, cell.entry, directory);
  }
}

Judgement judge_passes(const CellContext& cell, Passes& passes) {
  Judgement judgement;
  judgement.verdicts.resize(cell.steps);
  if (!cell.options.verify) return judgement;
  const Scene& scene = cell.data.sequence.scene();
  bool any_missed = false;
  for (std::size_t k = 0; k < cell.steps; ++k) {
    judgement.verdicts[k] = judge(scene, cell.data.truth[k], passes.first[k], cell.entry.judging, nullptr, cell.options.toi);
    any_missed = any_missed || judgement.verdicts[k].missed > 0;
  }
  if (any_missed && !passes.nondeterministic_step) audit(cell, passes, judgement);
  if (any_missed && passes.nondeterministic_step) {
    for (std::size_t k = 0; k < cell.steps; ++k) {
      judgement.verdicts[k] = judge(scene, cell.data.truth[k], passes.first[k], cell.entry.judging, nullptr, cell.options.toi);
    }
    judgement.miss_causes = {
        {"unexplained (its answers changed between two runs)", std::accumulate(judgement.verdicts.begin(), judgement.verdicts.end(), std::size_t{0},
                                                                               [](std::size_t n, const Verdict& v) { return n + v.missed; })}};
  }
  return judgement;
}

/// --write-answers: DIR/STRATEGY/SCENE (answers:DIR/STRATEGY reads it back), STRATEGY@δ when the run has several δ:
/// a folder of answers is for one δ.
void write_cell_answers(const CellContext& cell, const Passes& passes) {
  std::string folder = cell.spec.label;
  for (char& c : folder) c = c == '/' || c == ':' || c == '\\' ? '_' : c;
  if (cell.options.thicknesses.size() > 1) {
    folder += "@" + (cell.data.thickness_from == "scene" ? std::string("scene") : significant(cell.data.sequence.scene().thickness(), 17));
  }
  write_step_answers(passes.first, *cell.options.write_answers / folder / cell.data.label);
}

/// What the summary adds up over the steps.
struct Totals {
  std::vector<double> medians;
  std::size_t colliding = 0, reported = 0, missed = 0, culled = 0, tested = 0, false_alarms = 0;
  std::size_t colliding_face_shape = 0, missed_face_shape = 0;
  ToiVerdict toi;
  double candidates = 0, tests = 0, kept = 0, history = 0, device = 0;
  /// Each strategy counter (apccd's session_start, nf, pending_pairs, ...) over the steps: sum and max, since the
  /// paper reports averages and peaks, in the order the strategy reports them.
  std::vector<std::pair<std::string, std::pair<double, double>>> counters;
};

/// The verdict fields of step `k`'s record (with --verify exact), added to the totals.
void add_step_verdict(const CellContext& cell, const Passes& passes, const Verdict& verdict, std::size_t k, json& record, Totals& totals) {
  const Scene& scene = cell.data.sequence.scene();
  const CollisionSet& truth = cell.data.truth[k];
  record["colliding"] = truth.size();
  if (!scene.shape_objects().empty()) {
    record["colliding_face_shape"] = truth.face_shape().size();
    record["missed_face_shape"] = verdict.missed_face_shape;
  }
  record["missed"] = verdict.missed;
  if (verdict.missed > 0 && cell.entry.judging == strategies::Judging::elementary_pairs) {
    record["missed_pairs"] =
        missed_pair_records(scene, cell.data.frames[k], cell.data.frames[k + 1], truth, passes.first[k].collisions, kKeptMissedPairs);
  }
  record["missed_culled"] = verdict.culled;
  record["missed_tested"] = verdict.tested;
  record["false_alarms"] = verdict.false_alarms;
  if (cell.options.toi) {
    record["toi_checked"] = verdict.toi.checked;
    record["toi_late"] = verdict.toi.late;
    record["toi_error_max"] = verdict.toi.error_max;
  }
  totals.colliding += truth.size();
  totals.colliding_face_shape += truth.face_shape().size();
  totals.missed_face_shape += verdict.missed_face_shape;
  totals.toi.add(verdict.toi);
}

/// Step `k`'s record (docs/DESIGN.md §5), its counts added to the totals.
json step_record(const CellContext& cell, const Passes& passes, const Verdict& verdict, std::size_t k, Totals& totals) {
  const strategies::StepResult& r = passes.first[k];
  const strategies::Judging judging = cell.entry.judging;
  const double ms = median(passes.step_ms[k]);
  totals.medians.push_back(ms);
  json stages = json::object();
  for (const auto& [stage, value] : r.stages.entries()) stages[stage] = value;
  json record = {{"record", "step"},
                 {"schema", kRecordSchema},
                 {"scene", cell.data.label},
                 {"thickness", cell.data.sequence.scene().thickness()},
                 {"strategy", passes.resolved},
                 {"step", k},
                 {"ms", ms},
                 {"ms_repeats", passes.step_ms[k]},
                 {"stages", stages},
                 {"candidate_pairs", r.counters.candidate_triangle_pairs},
                 {"elementary_tests", r.counters.elementary_tests},
                 {"kept_bytes", r.counters.kept_bytes},
                 {"history_bytes", r.counters.history_bytes},
                 {"device_bytes", r.counters.device_bytes},
                 {"reported", reported_count(r, judging)}};
  // The digest of the answers (pairs and TOI bits), to compare two runs step by step; fcl's cells are judged by
  // triangle pairs and carry none.
  if (judging == strategies::Judging::elementary_pairs) record["answers"] = passes.digests[k];
  if (r.fault_count > 0) {
    record["errors"] = r.fault_count;
    record["error_first"] = r.faults.front().message;
  }
  for (const auto& [name, value] : r.counters.extra) {
    record[name] = value;
    auto it = std::find_if(totals.counters.begin(), totals.counters.end(), [&](const auto& total) { return total.first == name; });
    if (it == totals.counters.end()) it = totals.counters.insert(totals.counters.end(), {name, {0.0, value}});
    it->second.first += value;
    it->second.second = std::max(it->second.second, value);
  }
  if (cell.options.verify) add_step_verdict(cell, passes, verdict, k, record, totals);
  totals.reported += reported_count(r, judging);
  totals.missed += verdict.missed;
  totals.culled += verdict.culled;
  totals.tested += verdict.tested;
  totals.false_alarms += verdict.false_alarms;
  totals.candidates += static_cast<double>(r.counters.candidate_triangle_pairs);
  totals.tests += static_cast<double>(r.counters.elementary_tests);
  totals.kept = std::max(totals.kept, static_cast<double>(r.counters.kept_bytes));
  totals.history = std::max(totals.history, static_cast<double>(r.counters.history_bytes));
  totals.device = std::max(totals.device, static_cast<double>(r.counters.device_bytes));
  record.update(passes.environment);
  return record;
}

/// The summary's times: per step (median and mean), per stage, per pass, and the unattributed remainder.
json time_fields(const CellContext& cell, const Passes& passes, const Totals& totals) {
  const double steps = static_cast<double>(std::max<std::size_t>(cell.steps, 1));
  json stage_summary = json::object();
  // Mean per step too (a step without the stage adds 0): they add up to ms_per_step_mean, so a session's cheap
  // frames and its expensive start are both in them (apccd's medians show one or the other).
  json stage_mean = json::object();
  const double timed_steps = steps * static_cast<double>(std::max(1, cell.options.repeats));
  for (const auto& [stage, values] : passes.stage_ms) {
    stage_summary[stage] = median(values);
    stage_mean[stage] = std::accumulate(values.begin(), values.end(), 0.0) / timed_steps;
  }
  // Each timed pass's time over every step: what compare tests two runs' times with (a rank test over repeats).
  std::vector<double> pass_ms(static_cast<std::size_t>(std::max(1, cell.options.repeats)), 0.0);
  for (const std::vector<double>& repeats : passes.step_ms) {
    for (std::size_t r = 0; r < repeats.size() && r < pass_ms.size(); ++r) pass_ms[r] += repeats[r];
  }
  return {{"ms_per_step", median(totals.medians)},
          {"ms_per_step_mean", std::accumulate(totals.medians.begin(), totals.medians.end(), 0.0) / steps},
          {"ms_per_repeat", pass_ms},
          {"stage_ms", stage_summary},
          {"stage_ms_mean", stage_mean},
          {"unattributed_ms_mean", passes.unattributed_count ? passes.unattributed_sum / static_cast<double>(passes.unattributed_count) : 0.0}};
}

/// The summary's verdicts (with --verify exact): colliding, missed and why, false alarms, contact by objects, TOIs.
json verdict_fields(const CellContext& cell, const Judgement& judgement, const Totals& totals) {
  const Scene& scene = cell.data.sequence.scene();
  json fields = {{"colliding", totals.colliding},       {"missed", totals.missed},
                 {"missed_culled", totals.culled},      {"missed_tested", totals.tested},
                 {"false_alarms", totals.false_alarms}, {"miss_causes", judgement.miss_causes}};
  fields.update(contact_by_objects(scene, cell.data.truth, cell.steps));
  if (!scene.shape_objects().empty())
    fields.update(json{{"colliding_face_shape", totals.colliding_face_shape}, {"missed_face_shape", totals.missed_face_shape}});
  if (cell.options.toi) {
    const ToiVerdict& toi = totals.toi;
    fields.update(json{{"toi_checked", toi.checked},
                       {"toi_late", toi.late},
                       {"toi_missing", toi.missing},
                       {"toi_error_max", toi.error_max},
                       {"toi_error_mean", toi.checked ? toi.error_sum / static_cast<double>(toi.checked) : 0.0},
                       {"toi_error_median", toi.errors.empty() ? json() : json(percentile(toi.errors, 50))},
                       {"toi_error_p99", toi.errors.empty() ? json() : json(percentile(toi.errors, 99))}});
  }
  return fields;
}

/// The cell's summary (docs/DESIGN.md §5).
json cell_summary(const CellContext& cell, const Passes& passes, const Judgement& judgement, const Totals& totals, const json& faults) {
  const Scene& scene = cell.data.sequence.scene();
  const double steps = static_cast<double>(std::max<std::size_t>(cell.steps, 1));
  json counter_summary = json::object();
  for (const auto& [name, total] : totals.counters) counter_summary[name] = {{"mean", total.first / steps}, {"max", total.second}};
  json summary = {{"record", "summary"},
                  {"schema", kRecordSchema},
                  {"scene", cell.data.label},
                  {"strategy", passes.resolved},
                  // The strategy as --strategy gave it, when the cell ran (run --json sets it to this run's): what
                  // check and compare match a plugin's cell by, its resolved name holding absolute paths and digests.
                  {"spec", cell.spec.text},
                  {"triangles", scene.topology().num_faces()},
                  {"vertices", scene.topology().num_vertices()},
                  {"steps", cell.steps},
                  {"thickness", scene.thickness()}};
  summary.update(time_fields(cell, passes, totals));
  summary.update(json{{"counters", counter_summary},
                      {"candidate_pairs", totals.candidates / steps},
                      {"elementary_tests", totals.tests / steps},
                      {"kept_bytes", totals.kept},
                      {"history_bytes", totals.history},
                      {"device_bytes", totals.device},
                      {"host_peak_bytes", passes.host_peak},
                      {"host_peak_of", passes.peak_of_cell ? "cell" : "process"},
                      {"reported", totals.reported},
                      {"judged_by", cell.entry.judging == strategies::Judging::triangle_pairs ? "triangle pairs" : "elementary pairs"},
                      {"thickness_from", cell.data.thickness_from},
                      {"verified", cell.options.verify},
                      {"repeats", cell.options.repeats},
                      {"cell", std::filesystem::path(cell.cell_name).stem().string()},
                      {"errors", faults.at("errors")},
                      {"finished_at", utc_now()}});
  if (cell.options.verify) summary.update(verdict_fields(cell, judgement, totals));
  if (faults.contains("errors_written")) summary["errors_written"] = faults.at("errors_written");
  if (passes.nondeterministic_step) summary["nondeterministic_at_step"] = *passes.nondeterministic_step;
  summary.update(passes.environment);
  return summary;
}

}  // namespace

json run_cell(const SceneData& data, const strategies::StrategySpec& spec, const RunOptions& options, std::size_t steps, const std::string& cell_name,
              const CellProgress& progress, const std::string& planned_name) {
  const CellContext cell{data, spec, options, steps, cell_name, *spec.entry, spec.from_outside};
  Passes passes = time_passes(cell, progress, planned_name);
  const Judgement judgement = judge_passes(cell, passes);
  const std::filesystem::path fault_root = options.faults ? *options.faults : options.out / "faults";
  const json faults = record_faults(data.sequence.scene(), data.frames, passes.first,
                                    fault_root / safe_path_component(data.label) / std::filesystem::path(cell_name).stem());
  if (options.write_answers) write_cell_answers(cell, passes);
  json step_records = json::array();
  Totals totals;
  for (std::size_t k = 0; k < steps; ++k) step_records.push_back(step_record(cell, passes, judgement.verdicts[k], k, totals));
  return {{"summary", cell_summary(cell, passes, judgement, totals, faults)}, {"steps", step_records}};
}

}  // namespace ccd::harness
