#include "harness/run.hpp"

#include "ccd/config.hpp"
#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/procedural_scenes.hpp"
#include "datasets/scene_file.hpp"
#include "harness/json_output.hpp"
#include "harness/statistics.hpp"
#include "harness/truth_cache.hpp"
#include "strategies/strategy.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <unistd.h>

namespace ccd::harness {
namespace {

using nlohmann::json;

SceneSource generated(const std::string& name, std::map<std::string, double> parameters) {
  std::ostringstream label;
  label << name << "-r" << parameters.at("resolution") << "-f" << parameters.at("frames");
  return {label.str(), [name, parameters] {
            json block = {{"name", name}};
            for (const auto& [key, value] : parameters) block[key] = value;
            return datasets::scene_from_json({{"generator", block}}, ".", "suite scene " + name);
          }};
}

std::string command_output(const std::string& command) {
  std::string output;
  if (FILE* pipe = ::popen(command.c_str(), "r")) {
    char buffer[256];
    while (std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
    ::pclose(pipe);
  }
  while (!output.empty() && (output.back() == '\n' || output.back() == '\r')) output.pop_back();
  return output;
}

/// What every record carries: machine, build type, thread count, git revision.
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
    std::string revision = command_output("git -C '" + std::string(CCDBENCH_SOURCE_DIR) + "' rev-parse --short HEAD 2>/dev/null");
    if (revision.empty()) revision = "unknown";
    else if (!command_output("git -C '" + std::string(CCDBENCH_SOURCE_DIR) + "' status --porcelain --untracked-files=no 2>/dev/null").empty()) revision += "-dirty";
    return json{{"machine", std::string(host) + " (" + cpu + ", " + std::to_string(::sysconf(_SC_NPROCESSORS_ONLN)) + " cores)"},
                {"build_type", CCDBENCH_BUILD_TYPE},
                {"git_revision", revision}};
  }();
  json env = cached;
  env["threads"] = tbb::this_task_arena::max_concurrency();
  return env;
}

std::string sanitized(const std::string& text) {
  std::string out;
  for (char c : text) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.' ? c : '_';
  return out;
}

std::string cell_file_name(const std::string& scene, const std::string& strategy, double thickness, bool verify) {
  std::uint64_t hash = 14695981039346656037ull;
  std::ostringstream key;
  key << strategy << '|' << std::setprecision(17) << thickness << '|' << verify;
  for (char c : key.str()) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  std::ostringstream name;
  name << sanitized(scene) << "__" << sanitized(strategy.substr(0, strategy.find(':'))) << '_' << std::hex << hash << ".json";
  return name.str();
}

/// Misses and false alarms of one step; misses split by whether the strategy tested the pair.
struct Verdict {
  std::size_t missed = 0, culled = 0, tested = 0, false_alarms = 0;
};

template <class Pair>
bool in_sorted(const std::vector<Pair>& pairs, const Pair& p) {
  return std::binary_search(pairs.begin(), pairs.end(), p);
}

Verdict judge(const CollisionSet& truth, const CollisionSet& reported, const strategies::TestedPairs* tested) {
  Verdict verdict;
  const CollisionSet missed = set_difference(truth, reported);
  verdict.missed = missed.size();
  verdict.false_alarms = set_difference(reported, truth).size();
  if (tested) {
    for (const auto& c : missed.vertex_face()) (in_sorted(tested->vertex_face, c.pair) ? verdict.tested : verdict.culled) += 1;
    for (const auto& c : missed.edge_edge()) (in_sorted(tested->edge_edge, c.pair) ? verdict.tested : verdict.culled) += 1;
  }
  return verdict;
}

struct SceneData {
  std::string label;
  datasets::SceneSequence sequence;
  std::vector<std::vector<Vec3>> frames;
  std::vector<CollisionSet> truth;  // per step, when verifying
};

/// Runs one cell: repeats timed passes, judges the first against the truth, audits only when something is missed.
json run_cell(const SceneData& data, const std::string& spec, const RunOptions& options, std::size_t steps) {
  const Scene& scene = data.sequence.scene();
  std::vector<std::vector<double>> step_ms(steps);
  std::map<std::string, std::vector<double>> stage_ms;
  std::vector<strategies::StepResult> first_pass;
  std::string resolved;
  for (int repeat = 0; repeat < std::max(1, options.repeats); ++repeat) {
    auto strategy = strategies::make_strategy(spec);
    resolved = strategy->name();
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
  if (options.verify) {
    bool any_missed = false;
    for (std::size_t k = 0; k < steps; ++k) {
      verdicts[k] = judge(data.truth[k], first_pass[k].collisions, nullptr);
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
        verdicts[k] = judge(data.truth[k], first_pass[k].collisions, &*audit.tested);
      }
    }
  }
  json step_records = json::array();
  std::vector<double> medians;
  std::size_t colliding = 0, reported = 0, missed = 0, culled = 0, tested = 0, false_alarms = 0;
  double candidates = 0, tests = 0, history = 0;
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
                   {"reported", r.collisions.size()}};
    for (const auto& [name, value] : r.counters.extra) record[name] = value;
    if (options.verify) {
      record["colliding"] = data.truth[k].size();
      record["missed"] = verdicts[k].missed;
      record["missed_culled"] = verdicts[k].culled;
      record["missed_tested"] = verdicts[k].tested;
      record["false_alarms"] = verdicts[k].false_alarms;
      colliding += data.truth[k].size();
    }
    reported += r.collisions.size();
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
  for (const auto& [stage, values] : stage_ms) stage_summary[stage] = median(values);
  json summary = {{"record", "summary"},
                  {"scene", data.label},
                  {"strategy", resolved},
                  {"triangles", scene.topology().num_faces()},
                  {"steps", steps},
                  {"thickness", scene.thickness()},
                  {"ms_per_step", median(medians)},
                  {"stage_ms", stage_summary},
                  {"candidate_pairs", candidates / static_cast<double>(std::max<std::size_t>(steps, 1))},
                  {"elementary_tests", tests / static_cast<double>(std::max<std::size_t>(steps, 1))},
                  {"history_bytes", history},
                  {"reported", reported},
                  {"verified", options.verify},
                  {"repeats", options.repeats}};
  if (options.verify) {
    summary.update(json{{"colliding", colliding},
                        {"missed", missed},
                        {"missed_culled", culled},
                        {"missed_tested", tested},
                        {"false_alarms", false_alarms}});
  }
  summary.update(environment());
  return {{"summary", summary}, {"steps", step_records}};
}

std::string format(double value, int precision) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(precision) << value;
  return out.str();
}

/// The table rows, speed-ups only between cells of this invocation (DESIGN.md §5).
std::vector<std::vector<std::string>> table_rows(const std::vector<json>& summaries) {
  std::vector<std::vector<std::string>> rows;
  rows.push_back({"scene", "triangles", "steps", "strategy", "ms/step", "stages (ms)", "vs full", "candidates/step",
                  "tests/step", "colliding", "missed (culled/tested)", "false alarms"});
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
        if (other["scene"] == s["scene"] && !other.value("resumed", false) && name.rfind("full+", 0) == 0 &&
            narrow_token(name) == narrow_token(strategy) && !full) {
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
                    strategy, format(s["ms_per_step"].get<double>(), 3), stages, speedup,
                    format(s["candidate_pairs"].get<double>(), 0), format(s["elementary_tests"].get<double>(), 0),
                    verified ? std::to_string(s["colliding"].get<std::size_t>()) : "-",
                    verified ? std::to_string(s["missed"].get<std::size_t>()) + " (" + std::to_string(s["missed_culled"].get<std::size_t>()) +
                                   "/" + std::to_string(s["missed_tested"].get<std::size_t>()) + ")"
                             : "-",
                    verified ? std::to_string(s["false_alarms"].get<std::size_t>()) : "-"});
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
  const json env = environment();
  out << "\nMachine: " << env["machine"].get<std::string>() << "; build " << env["build_type"].get<std::string>()
      << ", " << env["threads"] << " threads, revision " << env["git_revision"].get<std::string>() << ".\n\n"
      << "![ms per step over the steps](ms_per_step.png)\n\n![stage breakdown per strategy](stages.png)\n\n"
      << "Plots drawn by `scripts/plot_run.py` from `steps.json`.\n";
  file.commit();
}

}  // namespace

std::vector<std::string> suite_names() { return {"ci", "default", "paper"}; }

std::vector<SceneSource> suite_scenes(const std::string& suite) {
  if (suite == "ci") {
    return {generated("spinning-ball", {{"resolution", 8}, {"frames", 5}}),
            generated("twist", {{"resolution", 8}, {"frames", 8}}),
            generated("pile", {{"resolution", 6}, {"frames", 8}, {"count", 2}})};
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

std::vector<json> run_benchmark(const RunOptions& options, std::ostream& out) {
  for (const std::string& spec : options.strategies) strategies::make_strategy(spec);  // unknown names fail first
  const TruthCache truth_cache(datasets::procedural_cache_root() / "truth");
  std::vector<json> cells;
  for (const SceneSource& source : options.scenes) {
    std::cerr << "run: loading " << source.label << "\n";
    SceneData data{source.label, source.load(), {}, {}};
    if (options.thickness) data.sequence.set_thickness(*options.thickness);
    std::size_t steps = data.sequence.num_steps();
    if (options.max_steps > 0) steps = std::min(steps, options.max_steps);
    if (steps == 0) throw InputError(source.label, {}, "the scene has no steps (one frame)");
    for (std::size_t k = 0; k <= steps; ++k) data.frames.push_back(data.sequence.frame(k));
    const Scene& scene = data.sequence.scene();
    std::vector<std::string> pending;
    for (const std::string& spec : options.strategies) {
      const std::string resolved = strategies::make_strategy(spec)->name();
      const auto file = options.out / "cells" / cell_file_name(source.label, resolved, scene.thickness(), options.verify);
      if (!options.fresh && std::filesystem::exists(file)) {
        std::ifstream in(file);
        json cell = json::parse(in);
        cell["summary"]["resumed"] = true;
        std::cerr << "run: " << source.label << " / " << resolved << ": kept from an earlier run (--fresh reruns it)\n";
        cells.push_back(std::move(cell));
      } else {
        pending.push_back(spec);
      }
    }
    if (pending.empty()) continue;
    if (options.verify) {
      for (std::size_t k = 0; k < steps; ++k) {
        bool computed = false;
        data.truth.push_back(truth_cache.truth(scene, data.frames[k], data.frames[k + 1], computed));
        std::cerr << "run: " << source.label << ": truth of step " << k + 1 << "/" << steps << (computed ? " computed" : " cached") << "\n";
      }
    }
    for (const std::string& spec : pending) {
      json cell = run_cell(data, spec, options, steps);
      const std::string resolved = cell["summary"]["strategy"];
      write_json_file(options.out / "cells" / cell_file_name(source.label, resolved, scene.thickness(), options.verify), cell);
      cells.push_back(std::move(cell));
    }
  }
  std::vector<json> summaries;
  for (const json& cell : cells) summaries.push_back(cell["summary"]);
  const auto rows = table_rows(summaries);
  print_table(rows, out);
  // Results: JSON lines of every step and summary of this invocation (kept cells included), written whole.
  {
    datasets::AtomicFile lines(options.out / "results.jsonl", std::ios::out);
    for (const json& cell : cells) {
      for (const json& step : cell["steps"]) lines.stream() << step.dump() << '\n';
      lines.stream() << cell["summary"].dump() << '\n';
    }
    lines.commit();
  }
  if (options.json) write_json_file(*options.json, summaries);
  if (options.report) {
    write_report(*options.report, rows, cells, options.command_line);
    out << "report: " << (*options.report / "README.md").string() << "\n";
  }
  out << "results: " << (options.out / "results.jsonl").string() << "\n";
  return summaries;
}

bool check_against_baseline(const json& baseline, const json& results, std::ostream& out) {
  if (!baseline.is_array() || !results.is_array()) throw std::invalid_argument("baseline and results must be JSON arrays");
  bool ok = true;
  for (const json& result : results) {
    if (!result.contains("missed")) {
      out << "FAIL " << result.value("scene", "?") << " / " << result.value("strategy", "?") << ": not verified (run with --verify exact)\n";
      ok = false;
      continue;
    }
    std::size_t allowed = 0;
    for (const json& entry : baseline) {
      if (entry.value("scene", "") == result["scene"] && entry.value("strategy", "") == result["strategy"]) {
        allowed = entry.value("max_missed", std::size_t{0});
      }
    }
    const std::size_t missed = result["missed"];
    if (missed > allowed) {
      out << "FAIL " << result["scene"].get<std::string>() << " / " << result["strategy"].get<std::string>() << ": missed "
          << missed << " (culled " << result["missed_culled"] << ", tested " << result["missed_tested"] << "), baseline allows "
          << allowed << "\n";
      ok = false;
    } else {
      out << "ok   " << result["scene"].get<std::string>() << " / " << result["strategy"].get<std::string>() << ": missed "
          << missed << " <= " << allowed << "\n";
    }
  }
  return ok;
}

}  // namespace ccd::harness
