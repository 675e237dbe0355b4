#include "harness/run/tables.hpp"

#include "datasets/atomic_file.hpp"
#include "harness/run/provenance.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "strategies/registry.hpp"

#include <algorithm>
#include <ostream>

namespace ccd::harness {
namespace {

using nlohmann::json;

constexpr const char* kTrianglePairMark = " (†)";
constexpr const char* kTrianglePairNote =
    "(†) judged by triangle pairs at δ = 0 (docs/DESIGN.md §3): a truth pair counts as found when a reported triangle pair "
    "contains both its primitives; false alarms are reported triangle pairs that contain no colliding pair.\n";
constexpr std::size_t kStrategyColumn = 2;

/// The cell whose time `s` is compared with: its strategy's baseline on the same scene at the same δ, with the same
/// narrow phase (any, for a strategy with elementary tests of its own), measured in this invocation on the same rank
/// and machine (MPI spreads cells over ranks and hosts). nullptr when there is none.
const json* baseline_of(const json& s, const std::vector<json>& summaries) {
  if (s.value("resumed", false)) return nullptr;
  const strategies::StrategyNames spec = strategies::strategy_names_of(s["strategy"]);
  const strategies::StrategyEntry& entry = strategies::find_strategy(spec.name);
  const std::string& baseline = entry.baseline;
  // Answers read from files have no time of their own to compare.
  if (baseline.empty()) return nullptr;
  for (const json& other : summaries) {
    if (other.value("resumed", false) || other["scene"] != s["scene"] || other["thickness"] != s["thickness"]) continue;
    if (other.value("rank", 0) != s.value("rank", 0) || other.value("machine", "") != s.value("machine", "")) continue;
    const strategies::StrategyNames candidate = strategies::strategy_names_of(other["strategy"]);
    if (candidate.name != baseline) continue;
    // With the same narrow phase; a strategy with tests of its own (a whole-step plugin) against the baseline as it
    // runs by default (full: conservative), never against another cell that uses a plugin.
    const std::string wanted = !spec.narrow_phase.empty() ? spec.narrow_phase : entry.takes_narrow_phase ? "" : narrowphase::kDefaultNarrowPhase;
    if (!wanted.empty() && candidate.narrow_phase != wanted) continue;
    return &other;
  }
  return nullptr;
}

}  // namespace

void attach_speedups(std::vector<json>& summaries) {
  std::vector<std::pair<json, json>> found;
  for (const json& s : summaries) {
    const json* base = baseline_of(s, summaries);
    if (base && s["ms_per_step"].get<double>() > 0) {
      found.emplace_back((*base)["ms_per_step"].get<double>() / s["ms_per_step"].get<double>(), (*base)["strategy"]);
    } else {
      found.emplace_back(nullptr, nullptr);
    }
  }
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    summaries[i]["speedup"] = found[i].first;
    summaries[i]["speedup_over"] = found[i].second;
  }
}

namespace {

/// One column of the run table: its header, alignment, whether the table shows it (given every summary), and its
/// cell of one summary. A column is one entry of run_columns().
struct RunColumn {
  const char* header;
  Table::Align align;
  bool (*shown)(const std::vector<json>& summaries);
  std::string (*cell)(const json& s);
};

bool always(const std::vector<json>&) { return true; }

bool any_toi(const std::vector<json>& summaries) {
  return std::any_of(summaries.begin(), summaries.end(), [](const json& s) { return s.contains("toi_late"); });
}

/// A count that only verification gives ("-" for a cell not verified).
std::string verified_count(const json& s, const char* field) {
  return s.value("verified", false) ? std::to_string(s[field].get<std::size_t>()) : std::string("-");
}

/// Memory by kind, MiB (a cell kept from before a field existed shows "-").
std::string mib(double bytes) { return fixed(bytes / (1024.0 * 1024.0), 0); }
std::string mib(const json& s, const char* field) { return s.contains(field) ? mib(s[field].get<double>()) : std::string("-"); }

const std::vector<RunColumn>& run_columns() {
  using Align = Table::Align;
  static const std::vector<RunColumn> columns = {
      {"scene", Align::left, always, [](const json& s) { return s["scene"].get<std::string>() + (s.value("resumed", false) ? " (resumed)" : ""); }},
      {"δ", Align::right, always,
       [](const json& s) { return significant(s["thickness"].get<double>(), 3) + (s.value("thickness_from", "") == "scene" ? " (scene's)" : ""); }},
      {"strategy", Align::left, always,
       [](const json& s) {
         return s.value("spec", s["strategy"].get<std::string>()) + (s.value("judged_by", "") == "triangle pairs" ? kTrianglePairMark : "");
       }},
      {"ms/step", Align::right, always, [](const json& s) { return fixed(s["ms_per_step"].get<double>(), 3); }},
      {"vs full", Align::right, always,
       [](const json& s) {
         return s.contains("speedup") && s["speedup"].is_number() ? fixed(s["speedup"].get<double>(), 2) + "x" : std::string("-");
       }},
      {"colliding", Align::right, always, [](const json& s) { return verified_count(s, "colliding"); }},
      {"missed (culled/tested)", Align::right, always,
       [](const json& s) {
         if (!s.value("verified", false)) return std::string("-");
         return verified_count(s, "missed") + " (" + verified_count(s, "missed_culled") + "/" + verified_count(s, "missed_tested") + ")";
       }},
      {"false alarms", Align::right, always, [](const json& s) { return verified_count(s, "false_alarms"); }},
      // An error is its own outcome (an answer a plugin or an answer file could not give), and answers that changed
      // between two passes are a verdict too: a column when any cell has either, or comes from outside ccdbench.
      {"errors", Align::right,
       [](const std::vector<json>& summaries) {
         return std::any_of(summaries.begin(), summaries.end(), [](const json& s) {
           return s.value("errors", 0) > 0 || s.contains("nondeterministic_at_step") || strategies::from_outside(s["strategy"]);
         });
       },
       [](const json& s) {
         std::string errors = std::to_string(s.value("errors", 0));
         if (s.contains("nondeterministic_at_step")) errors += "; answers changed between passes at step " + s["nondeterministic_at_step"].dump();
         return errors;
       }},
      {"TOI late (error max / mean)", Align::right, any_toi,
       [](const json& s) {
         if (!s.contains("toi_late")) return std::string("-");
         return std::to_string(s["toi_late"].get<std::size_t>()) + " of " + std::to_string(s["toi_checked"].get<std::size_t>()) + " (" +
                significant(s["toi_error_max"].get<double>(), 3) + " / " + significant(s["toi_error_mean"].get<double>(), 3) + ")";
       }},
      // The TOI error's 99th percentile (nearest rank), beside its max: one bad query or a tail.
      {"TOI error p99", Align::right, any_toi,
       [](const json& s) {
         return s.contains("toi_error_p99") && s["toi_error_p99"].is_number() ? significant(s["toi_error_p99"].get<double>(), 3) : "-";
       }},
      {"candidates/step", Align::right, always, [](const json& s) { return fixed(s["candidate_pairs"].get<double>(), 0); }},
      {"tests/step", Align::right, always, [](const json& s) { return fixed(s["elementary_tests"].get<double>(), 0); }},
      {"triangles", Align::right, always, [](const json& s) { return std::to_string(s["triangles"].get<std::size_t>()); }},
      {"steps", Align::right, always, [](const json& s) { return std::to_string(s["steps"].get<std::size_t>()); }},
      {"MiB kept/device/host peak", Align::right, always,
       [](const json& s) { return mib(s, "kept_bytes") + "/" + mib(s, "device_bytes") + "/" + mib(s, "host_peak_bytes"); }},
      // A step of the OpenCL backend runs within its memory budget (memory=), in as many chunks as that takes.
      {"device budget MiB (chunks/step max)", Align::right,
       [](const std::vector<json>& summaries) {
         return std::any_of(summaries.begin(), summaries.end(), [](const json& s) { return s["counters"].contains("device_budget_bytes"); });
       },
       [](const json& s) {
         const json& counters = s["counters"];
         if (!counters.contains("device_budget_bytes")) return std::string("-");
         const std::string chunks =
             counters.contains("device_chunks") ? fixed(counters["device_chunks"]["max"].get<double>(), 0) : std::string("whole");
         return mib(counters["device_budget_bytes"]["max"].get<double>()) + " (" + chunks + ")";
       }},
      {"stages (ms)", Align::left, always,
       [](const json& s) {
         std::string stages;
         for (const auto& [stage, ms] : s["stage_ms"].items()) stages += (stages.empty() ? "" : ", ") + stage + " " + fixed(ms.get<double>(), 2);
         return stages;
       }},
  };
  return columns;
}

}  // namespace

Table summary_table(const std::vector<json>& summaries) {
  std::vector<const RunColumn*> shown;
  std::vector<Table::Column> headers;
  for (const RunColumn& column : run_columns()) {
    if (!column.shown(summaries)) continue;
    shown.push_back(&column);
    headers.push_back({column.header, column.align});
  }
  Table table(std::move(headers));
  for (const json& s : summaries) {
    std::vector<std::string> row;
    for (const RunColumn* column : shown) row.push_back(column->cell(s));
    table.add_row(std::move(row));
  }
  return table;
}

std::string resolved_names(const std::vector<json>& summaries) {
  std::vector<std::pair<std::string, std::string>> names;
  for (const json& s : summaries) {
    const std::pair<std::string, std::string> name{s.value("spec", s["strategy"].get<std::string>()), s["strategy"].get<std::string>()};
    if (name.first != name.second && std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  std::string text;
  for (const auto& [spec, resolved] : names) text += "  " + spec + " = " + resolved + "\n";
  return text.empty() ? "" : "strategies as resolved (every default filled in; the name in --json, --out and the gate):\n" + text;
}

std::string summary_notes(const Table& table) {
  for (std::size_t r = 0; r < table.rows(); ++r) {
    if (table.row(r)[kStrategyColumn].find(kTrianglePairMark) != std::string::npos) return kTrianglePairNote;
  }
  return "";
}

void write_report(const std::filesystem::path& directory, const Table& table, const std::vector<json>& summaries, const std::vector<json>& cells,
                  const std::string& command) {
  json steps = json::array();
  for (const json& cell : cells) {
    for (const json& step : cell["steps"]) steps.push_back(step);
  }
  datasets::write_json_file(directory / kReportSteps, steps);
  datasets::write_json_file(directory / kReportSummaries, summaries);
  datasets::AtomicFile file(directory / kReportPage, std::ios::out);
  std::ostream& out = file.stream();
  out << "# ccdbench run\n\nEvery number below comes from one invocation (speed-ups only between cells of this run):\n\n```sh\n"
      << command << "\n```\n\n";
  table.print_markdown(out);
  out << '\n' << summary_notes(table);
  if (const std::string names = resolved_names(summaries); !names.empty()) out << "\n```\n" << names << "```\n";
  const json env = environment();
  out << "\nMachine: " << env["machine"].get<std::string>() << "; build " << env["build_type"].get<std::string>() << ", " << env["threads"]
      << " threads, revision " << env["git_revision"].get<std::string>() << ".\n\nProvenance (every record in "
      << "`summaries.json` and `steps.json` carries it, with the OpenCL platform, device and driver of OpenCL cells):";
  for (const auto& [name, value] : env["provenance"].items())
    out << " " << name << " " << (value.is_string() ? value.get<std::string>() : value.dump()) << ";";
  out << "\n\n"
      << "How to read it: `vs full` is a cell's speed-up over `full` with the same narrow phase on the same scene at the same\n"
      << "δ (> 1: faster); `missed` counts truth pairs the strategy did not report (culled: never tested; tested: its test\n"
      << "said no), a defect for a conservative method; false alarms are reported pairs that do not collide, a cost.\n\n"
      << "![speed-up over full](speedup.png)\n\n![colliding, missed and false alarms per cell](verdicts.png)\n\n"
      << "![median ms per step by stage](stages.png)\n\n![ms per step over the steps](ms_per_step.png)\n\n"
      << "Plots drawn by `scripts/plot_run.py` from `summaries.json` and `steps.json`.\n";
  file.commit();
}

}  // namespace ccd::harness
