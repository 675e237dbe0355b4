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
#include "strategies/plugin/child_process.hpp"
#include "strategies/registry.hpp"

#include <tbb/parallel_for.h>

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
  /// Each pass's start: making the strategy and its init on the first frame, ms.
  std::vector<double> setup_ms;
  std::map<std::string, std::vector<double>> stage_ms;
  /// Each timed step's ms less the sum of its own stages, over every pass: the time no stage names (the summary's
  /// ms_per_step_mean and stage_ms_mean are of medians and of means, and their difference is not this).
  double unattributed_sum = 0;
  std::size_t unattributed_count = 0;
  std::string resolved;
  RecordEnvironment environment;
  std::optional<std::size_t> nondeterministic_step;
  double host_peak = 0, child_peak = 0;
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
  const auto setup = std::chrono::steady_clock::now();
  auto strategy = strategies::make_strategy(cell.spec);
  passes.resolved = strategy->name();
  if (!planned_name.empty() && passes.resolved != planned_name) {
    // The key this cell would be kept under names other code than the code that would run.
    throw std::runtime_error(cell.data.label + " / " + cell.spec.label + ": it was planned as " + planned_name + " and would run as " +
                             passes.resolved + ": its code or answers changed during the run; the cells finished before are kept");
  }
  for (const auto& [name, value] : strategy->provenance()) passes.environment.provenance[name] = value;
  strategy->name_scene(cell.data.label);
  strategy->init(scene, cell.data.frames[0]);
  passes.setup_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - setup).count());
  for (std::size_t k = 0; k < cell.steps; ++k) {
    const StepView view{&scene, k, cell.data.frames[k], cell.data.frames[k + 1]};
    plugin::set_activity("cell " + cell.data.label + " / " + cell.spec.label + ", pass " + std::to_string(repeat + 1) + ", step " +
                         std::to_string(k) + " of steps 0-" + std::to_string(cell.steps - 1));
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
      // Every later pass's answers (pairs, TOI bits, and how many could not be given) against the first pass's, step
      // by step: harness work, after the timed call.
#if CCDBENCH_GUARD_REPEATS
    if (repeat > 0) {
      harness_pass("answers digest");
      if (answers_digest(result.collisions) != passes.digests[k] || result.fault_count != passes.first[k].fault_count) {
        not_deterministic(cell, passes, k, "passes");
      }
    }
#endif
    if (repeat == 0) passes.first.push_back(std::move(result));
    if (progress) progress(repeat, k, passes.resolved);
  }
  if (repeat == 0) {
    // The first pass keeps every step's answers: their digests are taken after it, side by side. One step after
    // another, a byte at a time, they took 0.1-0.2 s a cell of the paper's pile at its δ (5M contacts in 99 steps),
    // as long as some of its cells' steps.
    harness_pass("answers digest");
    passes.digests.resize(passes.first.size());
    tbb::parallel_for(std::size_t{0}, passes.first.size(), [&](std::size_t k) { passes.digests[k] = answers_digest(passes.first[k].collisions); });
  }
}

/// A cell's passes before the first: a time list for each step, the environment it runs in.
Passes no_passes(const CellContext& cell) {
  Passes passes;
  passes.step_ms.resize(cell.steps);
  passes.environment = environment().get<RecordEnvironment>();
  passes.peak_of_cell = true;
  return passes;
}

/// One timed pass and the memory it took: the host's peak over the pass (the strategy's memory and the frames it is
/// given; the truth and verification come after) and an isolated plugin's child's, ended with the pass's strategy.
/// The cell's peaks are the largest of its passes'.
void measured_pass(const CellContext& cell, Passes& passes, int repeat, const CellProgress& progress, const std::string& planned_name) {
  passes.peak_of_cell = reset_peak_resident() && passes.peak_of_cell;
  plugin::reset_children_peak();
  time_pass(cell, passes, repeat, progress, planned_name);
  const double child = static_cast<double>(plugin::children_peak_bytes());
  passes.child_peak = std::max(passes.child_peak, child);
  passes.host_peak = std::max(passes.host_peak, static_cast<double>(peak_resident_bytes()) + child);
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
    plugin::set_activity("cell " + cell.data.label + " / " + cell.spec.label + ", its audit pass, step " + std::to_string(k));
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
  std::size_t reported = 0;
  /// With --verify exact: the steps' verdicts added up.
  VerdictCounts verdicts;
  ToiVerdict toi;
  double candidates = 0, tests = 0, kept = 0, history = 0, device = 0;
  /// Each strategy counter (apccd's session_start, nf, pending_pairs, ...) over the steps: sum and max, since the
  /// paper reports averages and peaks, in the order the strategy reports them.
  std::vector<std::pair<std::string, std::pair<double, double>>> counters;
};

/// Step `k`'s verdict (with --verify exact), added to the totals.
StepVerdict step_verdict(const CellContext& cell, const Passes& passes, const Verdict& verdict, std::size_t k, Totals& totals) {
  const Scene& scene = cell.data.sequence.scene();
  const CollisionSet& truth = cell.data.truth[k];
  StepVerdict v;
  v.colliding = truth.size();
  v.missed = verdict.missed;
  v.missed_culled = verdict.culled;
  v.missed_tested = verdict.tested;
  v.false_alarms = verdict.false_alarms;
  if (!scene.shape_objects().empty()) {
    v.colliding_face_shape = truth.face_shape().size();
    v.missed_face_shape = verdict.missed_face_shape;
  }
  if (verdict.missed > 0 && cell.entry.judging == strategies::Judging::elementary_pairs) {
    v.missed_pairs = missed_pair_records(scene, cell.data.frames[k], cell.data.frames[k + 1], truth, passes.first[k].collisions, kKeptMissedPairs);
  }
  if (cell.options.toi) v.toi = StepVerdict::Toi{verdict.toi.checked, verdict.toi.late, verdict.toi.error_max};
  totals.verdicts += v;
  totals.toi.add(verdict.toi);
  return v;
}

/// Step `k`'s record (docs/DESIGN.md §5), its counts added to the totals.
StepRecord step_record(const CellContext& cell, const Passes& passes, const Verdict& verdict, std::size_t k, Totals& totals) {
  const strategies::StepResult& r = passes.first[k];
  const strategies::Judging judging = cell.entry.judging;
  StepRecord record;
  record.scene = cell.data.label;
  record.thickness = cell.data.sequence.scene().thickness();
  record.strategy = passes.resolved;
  record.step = k;
  record.ms = median(passes.step_ms[k]);
  record.ms_repeats = passes.step_ms[k];
  for (const auto& [stage, value] : r.stages.entries()) record.stages[stage] = value;
  record.candidate_pairs = r.counters.candidate_triangle_pairs;
  record.elementary_tests = r.counters.elementary_tests;
  record.kept_bytes = r.counters.kept_bytes;
  record.history_bytes = r.counters.history_bytes;
  record.device_bytes = r.counters.device_bytes;
  record.reported = reported_count(r, judging);
  totals.medians.push_back(record.ms);
  // The digest of the answers (pairs and TOI bits), to compare two runs step by step; fcl's cells are judged by
  // triangle pairs and carry none.
  if (judging == strategies::Judging::elementary_pairs) record.answers = passes.digests[k];
  if (r.fault_count > 0) {
    record.errors = r.fault_count;
    record.error_first = r.faults.front().message;
  }
  record.counters = r.counters.extra;
  for (const auto& [name, value] : r.counters.extra) {
    auto it = std::find_if(totals.counters.begin(), totals.counters.end(), [&](const auto& total) { return total.first == name; });
    if (it == totals.counters.end()) it = totals.counters.insert(totals.counters.end(), {name, {0.0, value}});
    it->second.first += value;
    it->second.second = std::max(it->second.second, value);
  }
  if (cell.options.verify) record.verdict = step_verdict(cell, passes, verdict, k, totals);
  totals.reported += record.reported;
  totals.candidates += static_cast<double>(r.counters.candidate_triangle_pairs);
  totals.tests += static_cast<double>(r.counters.elementary_tests);
  totals.kept = std::max(totals.kept, static_cast<double>(r.counters.kept_bytes));
  totals.history = std::max(totals.history, static_cast<double>(r.counters.history_bytes));
  totals.device = std::max(totals.device, static_cast<double>(r.counters.device_bytes));
  record.environment = passes.environment;
  return record;
}

/// The summary's times: per step (median and mean), per stage, per pass, and the unattributed remainder.
void add_times(const CellContext& cell, const Passes& passes, const Totals& totals, CellSummary& summary) {
  const double steps = static_cast<double>(std::max<std::size_t>(cell.steps, 1));
  // Mean per step too (a step without the stage adds 0): they add up to ms_per_step_mean, so a session's cheap
  // frames and its expensive start are both in them (apccd's medians show one or the other).
  const double timed_steps = steps * static_cast<double>(std::max(1, cell.options.repeats));
  for (const auto& [stage, values] : passes.stage_ms) {
    summary.stage_ms[stage] = median(values);
    summary.stage_ms_mean[stage] = std::accumulate(values.begin(), values.end(), 0.0) / timed_steps;
  }
  // Each timed pass's time over every step: what compare tests two runs' times with (a rank test over repeats).
  summary.ms_per_repeat.assign(static_cast<std::size_t>(std::max(1, cell.options.repeats)), 0.0);
  for (const std::vector<double>& repeats : passes.step_ms) {
    for (std::size_t r = 0; r < repeats.size() && r < summary.ms_per_repeat.size(); ++r) summary.ms_per_repeat[r] += repeats[r];
  }
  summary.ms_per_step = median(totals.medians);
  summary.ms_per_step_mean = std::accumulate(totals.medians.begin(), totals.medians.end(), 0.0) / steps;
  summary.unattributed_ms_mean = passes.unattributed_count ? passes.unattributed_sum / static_cast<double>(passes.unattributed_count) : 0.0;
  summary.setup_ms = passes.setup_ms.empty() ? 0.0 : median(passes.setup_ms);
}

/// The summary's verdicts (with --verify exact): colliding, missed and why, false alarms, contact by objects, TOIs.
CellVerdict cell_verdict(const CellContext& cell, const Judgement& judgement, const Totals& totals) {
  const Scene& scene = cell.data.sequence.scene();
  CellVerdict v;
  static_cast<VerdictCounts&>(v) = totals.verdicts;
  v.miss_causes = judgement.miss_causes;
  const json contact = contact_by_objects(scene, cell.data.truth, cell.steps);
  v.colliding_by_objects = contact.at("colliding_by_objects");
  v.faces_in_contact_by_objects = contact.at("faces_in_contact_by_objects");
  if (!scene.shape_objects().empty()) {  // also for a cell without steps
    v.colliding_face_shape = v.colliding_face_shape.value_or(0);
    v.missed_face_shape = v.missed_face_shape.value_or(0);
  }
  if (cell.options.toi) {
    const ToiVerdict& toi = totals.toi;
    v.toi.emplace();
    v.toi->checked = toi.checked;
    v.toi->late = toi.late;
    v.toi->missing = toi.missing;
    v.toi->error_max = toi.error_max;
    v.toi->error_mean = toi.checked ? toi.error_sum / static_cast<double>(toi.checked) : 0.0;
    if (!toi.errors.empty()) {
      v.toi->error_median = percentile(toi.errors, 50);
      v.toi->error_p99 = percentile(toi.errors, 99);
    }
  }
  return v;
}

/// The cell's summary (docs/DESIGN.md §5).
CellSummary cell_summary(const CellContext& cell, const Passes& passes, const Judgement& judgement, const Totals& totals, const json& faults) {
  const Scene& scene = cell.data.sequence.scene();
  const double steps = static_cast<double>(std::max<std::size_t>(cell.steps, 1));
  CellSummary summary;
  summary.scene = cell.data.label;
  summary.strategy = passes.resolved;
  // The strategy as --strategy gave it, when the cell ran (run --json sets it to this run's): what check and
  // compare match a plugin's cell by, its resolved name holding absolute paths and digests.
  summary.spec = cell.spec.text;
  summary.triangles = scene.topology().num_faces();
  summary.vertices = scene.topology().num_vertices();
  summary.steps = cell.steps;
  summary.thickness = scene.thickness();
  add_times(cell, passes, totals, summary);
  for (const auto& [name, total] : totals.counters) summary.counters[name] = {total.first / steps, total.second};
  summary.candidate_pairs = totals.candidates / steps;
  summary.elementary_tests = totals.tests / steps;
  summary.kept_bytes = totals.kept;
  summary.history_bytes = totals.history;
  summary.device_bytes = totals.device;
  summary.host_peak_bytes = passes.host_peak;
  summary.host_peak_of = passes.peak_of_cell ? "cell" : "process";
  summary.child_peak_bytes = passes.child_peak;
  summary.reported = totals.reported;
  summary.judged_by = cell.entry.judging;
  summary.thickness_from_scene = cell.data.thickness_from == "scene";
  summary.verified = cell.options.verify;
  summary.repeats = cell.options.repeats;
  summary.cell = std::filesystem::path(cell.cell_name).stem().string();
  summary.errors = faults.at("errors").get<std::size_t>();
  summary.finished_at = utc_now();
  if (cell.options.verify) summary.verdict = cell_verdict(cell, judgement, totals);
  if (faults.contains("errors_written")) summary.errors_written = faults.at("errors_written").get<std::string>();
  summary.nondeterministic_at_step = passes.nondeterministic_step;
  summary.environment = passes.environment;
  return summary;
}

}  // namespace

namespace {

/// A cell's record from its timed passes: judged against the truth (audited where it missed), its faults and
/// answers written.
CellRecord finish_cell(const CellContext& cell, Passes& passes) {
  const Judgement judgement = judge_passes(cell, passes);
  const std::filesystem::path fault_root = cell.options.faults ? *cell.options.faults : cell.options.out / "faults";
  const json faults = record_faults(cell.data.sequence.scene(), cell.data.frames, passes.first,
                                    fault_root / safe_path_component(cell.data.label) / std::filesystem::path(cell.cell_name).stem(), cell.spec.text);
  if (cell.options.write_answers) write_cell_answers(cell, passes);
  CellRecord record;
  Totals totals;
  for (std::size_t k = 0; k < cell.steps; ++k) record.steps.push_back(step_record(cell, passes, judgement.verdicts[k], k, totals));
  record.summary = cell_summary(cell, passes, judgement, totals, faults);
  return record;
}

}  // namespace

CellRecord run_cell(const SceneData& data, const strategies::StrategySpec& spec, const RunOptions& options, std::size_t steps,
                    const std::string& cell_name, const CellProgress& progress, const std::string& planned_name) {
  const CellContext cell{data, spec, options, steps, cell_name, *spec.entry, spec.from_outside};
  Passes passes = no_passes(cell);
  for (int repeat = 0; repeat < std::max(1, options.repeats); ++repeat) measured_pass(cell, passes, repeat, progress, planned_name);
  plugin::set_activity({});
  return finish_cell(cell, passes);
}

std::vector<CellRecord> run_cells_interleaved(const SceneData& data, const std::vector<CellToRun>& cells, const RunOptions& options,
                                              std::size_t steps, const CellProgress& progress, const std::string& group) {
  std::vector<CellContext> contexts;
  std::vector<Passes> passes;
  for (const CellToRun& c : cells) {
    contexts.push_back({data, *c.spec, options, steps, c.cell_name, *c.spec->entry, c.spec->from_outside});
    passes.push_back(no_passes(contexts.back()));
  }
  // Turns in alternating order (A B, B A, A B, ...): a cell's place in a turn (a cache warmed by the cell before it,
  // a clock that ramps up) favours no cell, so each pair of passes differs by the code alone, as compare's paired
  // test assumes.
  for (int repeat = 0; repeat < std::max(1, options.repeats); ++repeat) {
    for (std::size_t k = 0; k < cells.size(); ++k) {
      const std::size_t i = repeat % 2 == 0 ? k : cells.size() - 1 - k;
      measured_pass(contexts[i], passes[i], repeat, progress, cells[i].planned_name);
    }
  }
  plugin::set_activity({});
  std::vector<CellRecord> records;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    records.push_back(finish_cell(contexts[i], passes[i]));
    records.back().summary.interleave_group = group;
  }
  return records;
}

}  // namespace ccd::harness
