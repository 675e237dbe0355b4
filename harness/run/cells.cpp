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

}  // namespace

json run_cell(const SceneData& data, const std::string& spec, const RunOptions& options, std::size_t steps, const std::string& cell_name,
              const CellProgress& progress, const std::string& planned_name) {
  const Scene& scene = data.sequence.scene();
  std::vector<std::vector<double>> step_ms(steps);
  std::map<std::string, std::vector<double>> stage_ms;
  std::vector<strategies::StepResult> first_pass;
  std::string resolved;
  const strategies::StrategyEntry& strategy_entry = strategies::strategy_entry_of(spec);
  const strategies::Judging judging = strategy_entry.judging;
  json environment_of_cell = environment();
  // The host's peak over the cell's timed passes: the strategy's memory and the frames it is given (the truth and
  // verification come after).
  const bool peak_of_cell = reset_peak_resident();
  // Each timed step's ms less the sum of its own stages, over every pass: the time no stage names (the summary's
  // ms_per_step_mean and stage_ms_mean are of medians and of means, and their difference is not this).
  double unattributed_sum = 0;
  std::size_t unattributed_count = 0;
  // Code from outside ccdbench may answer differently when asked again: its cell then says so (and `check` fails it
  // unless its baseline allows it), where a built-in strategy's would be a defect that ends the run.
  const bool from_outside = strategies::from_outside(spec);
  std::optional<std::size_t> nondeterministic_step;
  std::vector<std::string> first_digests;
  auto not_deterministic = [&](std::size_t k, const char* how) {
    if (!from_outside) {
      throw std::runtime_error(resolved + " gave different answers on two " + how + " of step " + std::to_string(k) + " of " + data.label +
                               ": the strategy is not deterministic");
    }
    if (!nondeterministic_step || k < *nondeterministic_step) nondeterministic_step = k;
  };
  for (int repeat = 0; repeat < std::max(1, options.repeats); ++repeat) {
    auto strategy = strategies::make_strategy(spec);
    resolved = strategy->name();
    if (!planned_name.empty() && resolved != planned_name) {
      // The key this cell would be kept under names other code than the code that would run.
      throw std::runtime_error(data.label + " / " + strategies::short_label(spec) + ": it was planned as " + planned_name + " and would run as " +
                               resolved + ": its code or answers changed during the run; the cells finished before are kept");
    }
    for (const auto& [name, value] : strategy->provenance()) environment_of_cell["provenance"][name] = value;
    strategy->name_scene(data.label);
    strategy->init(scene, data.frames[0]);
    for (std::size_t k = 0; k < steps; ++k) {
      const StepView view{&scene, k, data.frames[k], data.frames[k + 1]};
      plugin::set_activity("cell " + data.label + " / " + strategies::short_label(spec) + ", pass " + std::to_string(repeat + 1) + ", step " +
                           std::to_string(k + 1) + " of " + std::to_string(steps));
      std::optional<strategies::StepResult> answered;
      const auto start = std::chrono::steady_clock::now();
      {
        const TimedRegion timed;
        answered = strategy->step(view, false);
      }
      step_ms[k].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      strategies::StepResult result = std::move(*answered);
      unattributed_sum += step_ms[k].back() - result.stages.total_milliseconds();
      ++unattributed_count;
      for (const auto& [stage, ms] : result.stages.entries()) stage_ms[stage].push_back(ms);
      // Every repeat's answers (pairs, TOI bits, and how many could not be given) against the first pass's, step
      // by step: harness work, after the timed call.
      harness_pass("answers digest");
      const std::string digest = answers_digest(result.collisions);
      if (repeat == 0) {
        first_digests.push_back(digest);
#if CCDBENCH_GUARD_REPEATS
      } else if (digest != first_digests[k] || result.fault_count != first_pass[k].fault_count) {
        not_deterministic(k, "passes");
#endif
      }
      if (repeat == 0) first_pass.push_back(std::move(result));
      if (progress) progress(repeat, k, resolved);
    }
  }
  plugin::set_activity({});
  const double host_peak = static_cast<double>(peak_resident_bytes());
  std::vector<Verdict> verdicts(steps);
  std::vector<strategies::TestedPairs> audited;
  json miss_causes = json::object();
  if (options.verify) {
    bool any_missed = false;
    for (std::size_t k = 0; k < steps; ++k) {
      verdicts[k] = judge(scene, data.truth[k], first_pass[k], judging, nullptr, options.toi);
      any_missed = any_missed || verdicts[k].missed > 0;
    }
    // A cell whose answers changed between passes has its misses left unexplained (below).
    if (any_missed && !nondeterministic_step) {
      // Audit pass, outside every timed region: which misses were never tested (culled) and which tested wrong.
      auto strategy = strategies::make_strategy(spec);
      strategy->name_scene(data.label);
      strategy->init(scene, data.frames[0]);
      for (std::size_t k = 0; k < steps && !nondeterministic_step; ++k) {
        plugin::set_activity("cell " + data.label + " / " + strategies::short_label(spec) + ", its audit pass, step " + std::to_string(k + 1));
        strategies::StepResult audit = strategy->step({&scene, k, data.frames[k], data.frames[k + 1]}, true);
        if (answers_digest(audit.collisions) != first_digests[k] || audit.fault_count != first_pass[k].fault_count) {
          not_deterministic(k, "runs");
          break;
        }
        // A strategy that tests no pair ccdbench sees (a whole-step plugin, answer files) has no audit: its misses
        // are explained by its entry (explain_miss).
        verdicts[k] = judge(scene, data.truth[k], first_pass[k], judging, audit.tested ? &*audit.tested : nullptr, options.toi);
        audited.push_back(audit.tested ? std::move(*audit.tested) : strategies::TestedPairs{});
      }
      if (!nondeterministic_step) {
        std::optional<std::filesystem::path> directory;
        if (options.misses) directory = *options.misses / safe_path_component(data.label) / std::filesystem::path(cell_name).stem();
        miss_causes = record_misses(scene, data.frames, data.truth, first_pass, audited, strategy_entry, directory);
      }
    }
    if (any_missed && nondeterministic_step) {
      audited.clear();
      for (std::size_t k = 0; k < steps; ++k) verdicts[k] = judge(scene, data.truth[k], first_pass[k], judging, nullptr, options.toi);
      miss_causes = {
          {"unexplained (its answers changed between two runs)",
           std::accumulate(verdicts.begin(), verdicts.end(), std::size_t{0}, [](std::size_t n, const Verdict& v) { return n + v.missed; })}};
    }
  }
  const std::filesystem::path fault_root = options.faults ? *options.faults : options.out / "faults";
  const json faults =
      record_faults(scene, data.frames, first_pass, fault_root / safe_path_component(data.label) / std::filesystem::path(cell_name).stem());
  if (options.write_answers) {
    // DIR/STRATEGY/SCENE (answers:DIR/STRATEGY reads it back), STRATEGY@δ when the run has several δ: a folder of
    // answers is for one δ.
    std::string folder = strategies::short_label(spec);
    for (char& c : folder) c = c == '/' || c == ':' || c == '\\' ? '_' : c;
    if (options.thicknesses.size() > 1) folder += "@" + (data.thickness_from == "scene" ? std::string("scene") : significant(scene.thickness(), 17));
    write_step_answers(first_pass, *options.write_answers / folder / data.label);
  }
  json step_records = json::array();
  std::vector<double> medians;
  std::size_t colliding = 0, reported = 0, missed = 0, culled = 0, tested = 0, false_alarms = 0;
  std::size_t colliding_face_shape = 0, missed_face_shape = 0;
  ToiVerdict toi_total;
  double candidates = 0, tests = 0, kept = 0, history = 0, device = 0;
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
                   {"schema", kRecordSchema},
                   {"scene", data.label},
                   {"thickness", scene.thickness()},
                   {"strategy", resolved},
                   {"step", k},
                   {"ms", ms},
                   {"ms_repeats", step_ms[k]},
                   {"stages", stages},
                   {"candidate_pairs", r.counters.candidate_triangle_pairs},
                   {"elementary_tests", r.counters.elementary_tests},
                   {"kept_bytes", r.counters.kept_bytes},
                   {"history_bytes", r.counters.history_bytes},
                   {"device_bytes", r.counters.device_bytes},
                   {"reported", reported_count(r, judging)}};
    // The digest of the answers (pairs and TOI bits), to compare two runs step by step; fcl's cells are judged by
    // triangle pairs and carry none.
    if (judging == strategies::Judging::elementary_pairs) {
      record["answers"] = first_digests[k];
    }
    if (r.fault_count > 0) {
      record["errors"] = r.fault_count;
      record["error_first"] = r.faults.front().message;
    }
    for (const auto& [name, value] : r.counters.extra) {
      record[name] = value;
      auto it = std::find_if(counter_totals.begin(), counter_totals.end(), [&](const auto& total) { return total.first == name; });
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
      if (verdicts[k].missed > 0 && judging == strategies::Judging::elementary_pairs) {
        record["missed_pairs"] = missed_pair_records(scene, data.frames[k], data.frames[k + 1], data.truth[k], r.collisions, kKeptMissedPairs);
      }
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
    kept = std::max(kept, static_cast<double>(r.counters.kept_bytes));
    history = std::max(history, static_cast<double>(r.counters.history_bytes));
    device = std::max(device, static_cast<double>(r.counters.device_bytes));
    record.update(environment_of_cell);
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
  // Each timed pass's time over every step: what compare tests two runs' times with (a rank test over repeats).
  std::vector<double> pass_ms(static_cast<std::size_t>(std::max(1, options.repeats)), 0.0);
  for (const std::vector<double>& repeats : step_ms) {
    for (std::size_t r = 0; r < repeats.size() && r < pass_ms.size(); ++r) pass_ms[r] += repeats[r];
  }
  json summary = {{"record", "summary"},
                  {"schema", kRecordSchema},
                  {"scene", data.label},
                  {"strategy", resolved},
                  // The strategy as --strategy gave it, when the cell ran (run --json sets it to this run's): what
                  // check and compare match a plugin's cell by, its resolved name holding absolute paths and digests.
                  {"spec", spec},
                  {"triangles", scene.topology().num_faces()},
                  {"vertices", scene.topology().num_vertices()},
                  {"steps", steps},
                  {"thickness", scene.thickness()},
                  {"ms_per_step", median(medians)},
                  {"ms_per_step_mean", ms_sum / static_cast<double>(std::max<std::size_t>(steps, 1))},
                  {"ms_per_repeat", pass_ms},
                  {"stage_ms", stage_summary},
                  {"stage_ms_mean", stage_mean},
                  {"unattributed_ms_mean", unattributed_count ? unattributed_sum / static_cast<double>(unattributed_count) : 0.0},
                  {"counters", counter_summary},
                  {"candidate_pairs", candidates / static_cast<double>(std::max<std::size_t>(steps, 1))},
                  {"elementary_tests", tests / static_cast<double>(std::max<std::size_t>(steps, 1))},
                  {"kept_bytes", kept},
                  {"history_bytes", history},
                  {"device_bytes", device},
                  {"host_peak_bytes", host_peak},
                  {"host_peak_of", peak_of_cell ? "cell" : "process"},
                  {"reported", reported},
                  {"judged_by", judging == strategies::Judging::triangle_pairs ? "triangle pairs" : "elementary pairs"},
                  {"thickness_from", data.thickness_from},
                  {"verified", options.verify},
                  {"repeats", options.repeats},
                  {"cell", std::filesystem::path(cell_name).stem().string()},
                  {"errors", faults.at("errors")},
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
                          {"toi_error_mean", toi_total.checked ? toi_total.error_sum / static_cast<double>(toi_total.checked) : 0.0},
                          {"toi_error_median", toi_total.errors.empty() ? json() : json(percentile(toi_total.errors, 50))},
                          {"toi_error_p99", toi_total.errors.empty() ? json() : json(percentile(toi_total.errors, 99))}});
    }
  }
  if (faults.contains("errors_written")) summary["errors_written"] = faults.at("errors_written");
  if (nondeterministic_step) summary["nondeterministic_at_step"] = *nondeterministic_step;
  summary.update(environment_of_cell);
  return {{"summary", summary}, {"steps", step_records}};
}

}  // namespace ccd::harness
