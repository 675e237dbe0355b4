#include "harness/run/tables.hpp"

#include "datasets/atomic_file.hpp"
#include "harness/run/provenance.hpp"
#include "harness/run/result_set.hpp"
#include "harness/work_queue.hpp"
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
const CellSummary* baseline_of(const CellSummary& s, const std::vector<CellRecord>& cells) {
  if (s.resumed) return nullptr;
  const strategies::StrategyNames spec = strategies::strategy_names_of(s.strategy);
  const strategies::StrategyEntry& entry = strategies::find_strategy(spec.name);
  const std::string& baseline = entry.baseline;
  // Answers read from files have no time of their own to compare.
  if (baseline.empty()) return nullptr;
  for (const CellRecord& cell : cells) {
    const CellSummary& other = cell.summary;
    if (other.resumed || other.scene != s.scene || other.thickness != s.thickness) continue;
    if (other.environment.rank != s.environment.rank || other.environment.machine != s.environment.machine) continue;
    const strategies::StrategyNames candidate = strategies::strategy_names_of(other.strategy);
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

void attach_speedups(std::vector<CellRecord>& cells) {
  std::vector<CellSummary::Speedup> found;
  for (const CellRecord& cell : cells) {
    const CellSummary* base = baseline_of(cell.summary, cells);
    CellSummary::Speedup speedup;
    if (base && cell.summary.ms_per_step > 0) {
      speedup.ratio = base->ms_per_step / cell.summary.ms_per_step;
      speedup.over = base->strategy;
    }
    found.push_back(speedup);
  }
  for (std::size_t i = 0; i < cells.size(); ++i) cells[i].summary.speedup = found[i];
}

namespace {

/// One column of the run table: its header, alignment, whether the table shows it (given every summary), and its
/// cell of one summary. A column is one entry of run_columns().
struct RunColumn {
  const char* header;
  Table::Align align;
  bool (*shown)(const std::vector<CellRecord>& cells);
  std::string (*cell)(const CellSummary& s);
};

bool always(const std::vector<CellRecord>&) { return true; }

bool any_toi(const std::vector<CellRecord>& cells) {
  return std::any_of(cells.begin(), cells.end(), [](const CellRecord& c) { return c.summary.verdict && c.summary.verdict->toi; });
}

/// A count that only verification gives ("-" for a cell not verified).
std::string verified_count(const CellSummary& s, std::size_t VerdictCounts::*count) {
  return s.verified && s.verdict ? std::to_string((*s.verdict).*count) : std::string("-");
}

/// Memory, MiB.
std::string mib(double bytes) { return fixed(bytes / (1024.0 * 1024.0), 0); }

/// A strategy counter's maximum over the steps, if the cell counted it.
std::optional<double> counter_max(const CellSummary& s, const char* name) {
  const auto it = s.counters.find(name);
  return it == s.counters.end() ? std::nullopt : std::optional<double>(it->second.max);
}

const std::vector<RunColumn>& run_columns() {
  using Align = Table::Align;
  static const std::vector<RunColumn> columns = {
      {"scene", Align::left, always, [](const CellSummary& s) { return s.scene + (s.resumed ? " (resumed)" : ""); }},
      {"δ", Align::right, always, [](const CellSummary& s) { return significant(s.thickness, 3) + (s.thickness_from_scene ? " (scene's)" : ""); }},
      {"strategy", Align::left, always,
       [](const CellSummary& s) { return s.given() + (s.judged_by == strategies::Judging::triangle_pairs ? kTrianglePairMark : ""); }},
      {"ms/step", Align::right, always, [](const CellSummary& s) { return fixed(s.ms_per_step, 3); }},
      {"vs full", Align::right, always,
       [](const CellSummary& s) { return s.speedup && s.speedup->ratio ? fixed(*s.speedup->ratio, 2) + "x" : std::string("-"); }},
      {"colliding", Align::right, always, [](const CellSummary& s) { return verified_count(s, &VerdictCounts::colliding); }},
      {"missed (culled/tested)", Align::right, always,
       [](const CellSummary& s) {
         if (!s.verified || !s.verdict) return std::string("-");
         return verified_count(s, &VerdictCounts::missed) + " (" + verified_count(s, &VerdictCounts::missed_culled) + "/" +
                verified_count(s, &VerdictCounts::missed_tested) + ")";
       }},
      {"false alarms", Align::right, always, [](const CellSummary& s) { return verified_count(s, &VerdictCounts::false_alarms); }},
      // An error is its own outcome (an answer a plugin or an answer file could not give), and answers that changed
      // between two passes are a verdict too: a column when any cell has either, or comes from outside ccdbench.
      {"errors", Align::right,
       [](const std::vector<CellRecord>& cells) {
         return std::any_of(cells.begin(), cells.end(), [](const CellRecord& c) {
           return c.summary.errors > 0 || c.summary.nondeterministic_at_step || strategies::from_outside(c.summary.strategy);
         });
       },
       [](const CellSummary& s) {
         std::string errors = std::to_string(s.errors);
         if (s.nondeterministic_at_step) errors += "; answers changed between passes at step " + std::to_string(*s.nondeterministic_at_step);
         return errors;
       }},
      {"TOI late (error max / mean)", Align::right, any_toi,
       [](const CellSummary& s) {
         if (!s.verdict || !s.verdict->toi) return std::string("-");
         const CellVerdict::Toi& toi = *s.verdict->toi;
         return std::to_string(toi.late) + " of " + std::to_string(toi.checked) + " (" + significant(toi.error_max, 3) + " / " +
                significant(toi.error_mean, 3) + ")";
       }},
      // The TOI error's 99th percentile (nearest rank), beside its max: one bad query or a tail.
      {"TOI error p99", Align::right, any_toi,
       [](const CellSummary& s) {
         return s.verdict && s.verdict->toi && s.verdict->toi->error_p99 ? significant(*s.verdict->toi->error_p99, 3) : std::string("-");
       }},
      {"candidates/step", Align::right, always, [](const CellSummary& s) { return fixed(s.candidate_pairs, 0); }},
      {"tests/step", Align::right, always, [](const CellSummary& s) { return fixed(s.elementary_tests, 0); }},
      {"triangles", Align::right, always, [](const CellSummary& s) { return std::to_string(s.triangles); }},
      {"steps", Align::right, always, [](const CellSummary& s) { return std::to_string(s.steps); }},
      {"MiB kept/device/host peak", Align::right, always,
       [](const CellSummary& s) { return mib(s.kept_bytes) + "/" + mib(s.device_bytes) + "/" + mib(s.host_peak_bytes); }},
      // A step of the OpenCL backend runs within its memory budget (memory=), in as many chunks as that takes.
      {"device budget MiB (chunks/step max)", Align::right,
       [](const std::vector<CellRecord>& cells) {
         return std::any_of(cells.begin(), cells.end(),
                            [](const CellRecord& c) { return counter_max(c.summary, strategies::kDeviceBudgetCounter).has_value(); });
       },
       [](const CellSummary& s) {
         const std::optional<double> budget = counter_max(s, strategies::kDeviceBudgetCounter),
                                     chunks = counter_max(s, strategies::kDeviceChunksCounter);
         if (!budget) return std::string("-");
         return mib(*budget) + " (" + (chunks ? fixed(*chunks, 0) : std::string("whole")) + ")";
       }},
      {"stages (ms)", Align::left, always,
       [](const CellSummary& s) {
         std::string stages;
         for (const auto& [stage, ms] : s.stage_ms) stages += (stages.empty() ? "" : ", ") + stage + " " + fixed(ms, 2);
         return stages;
       }},
  };
  return columns;
}

}  // namespace

Table summary_table(const std::vector<CellRecord>& cells) {
  std::vector<const RunColumn*> shown;
  std::vector<Table::Column> headers;
  for (const RunColumn& column : run_columns()) {
    if (!column.shown(cells)) continue;
    shown.push_back(&column);
    headers.push_back({column.header, column.align});
  }
  Table table(std::move(headers));
  for (const CellRecord& cell : cells) {
    std::vector<std::string> row;
    for (const RunColumn* column : shown) row.push_back(column->cell(cell.summary));
    table.add_row(std::move(row));
  }
  return table;
}

std::string resolved_names(const std::vector<CellRecord>& cells) {
  std::vector<std::pair<std::string, std::string>> names;
  for (const CellRecord& cell : cells) {
    const std::pair<std::string, std::string> name{cell.summary.given(), cell.summary.strategy};
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

/// The summaries as --json and --report write them (each through the one serializer).
json summaries_json(const std::vector<CellRecord>& cells) {
  json summaries = json::array();
  for (const CellRecord& cell : cells) summaries.push_back(cell.summary);
  return summaries;
}

void write_report(const std::filesystem::path& directory, const Table& table, const std::vector<CellRecord>& cells, const std::string& command) {
  json steps = json::array();
  for (const CellRecord& cell : cells) {
    for (const StepRecord& step : cell.steps) steps.push_back(step);
  }
  datasets::write_json_file(directory / kReportSteps, steps);
  datasets::write_json_file(directory / kReportSummaries, summaries_json(cells));
  datasets::AtomicFile file(directory / kReportPage, std::ios::out);
  std::ostream& out = file.stream();
  out << "# ccdbench run\n\nEvery number below comes from one invocation (speed-ups only between cells of this run):\n\n```sh\n"
      << command << "\n```\n\n";
  table.print_markdown(out);
  out << '\n' << summary_notes(table);
  if (const std::string names = resolved_names(cells); !names.empty()) out << "\n```\n" << names << "```\n";
  const RecordEnvironment env = environment().get<RecordEnvironment>();
  out << "\nMachine: " << env.machine << "; build " << env.build_type << ", " << env.threads << " threads, revision " << env.git_revision
      << ".\n\nProvenance (every record in "
      << "`summaries.json` and `steps.json` carries it, with the OpenCL platform, device and driver of OpenCL cells):";
  for (const auto& [name, value] : env.provenance.items())
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

void report_run(const RunResult& result, const RunOptions& options, std::ostream& out) {
  if (rank_info().rank != 0) return;
  const Table table = summary_table(result.cells);
  table.print(out);
  out << summary_notes(table) << resolved_names(result.cells);
  for (const CellRecord& cell : result.cells) {
    const CellSummary& s = cell.summary;
    if (s.errors == 0) continue;
    out << "errors: " << s.scene << " / " << s.given() << ": " << s.errors
        << " answers could not be taken (counted apart, and as the plugin's errors= key says); written to "
        << s.errors_written.value_or("(kept from an earlier run)") << "/FAULTS.txt\n";
  }
  for (const LeftOut& refused : result.left_out) {
    out << "left out: " << refused.spec << " on " << refused.scenes.size() << " scene" << (refused.scenes.size() == 1 ? "" : "s") << " (";
    for (std::size_t i = 0; i < refused.scenes.size(); ++i) out << (i ? ", " : "") << refused.scenes[i];
    out << "), which it refuses; the first said: " << refused.reason << "\n";
  }
  if (options.json) datasets::write_json_file(*options.json, summaries_json(result.cells));
  if (options.report) {
    write_report(*options.report, table, result.cells, options.command_line);
    out << "report: " << (*options.report / kReportPage).string() << "\n";
  }
  out << "results: " << (options.out / kResultsLogFile).string() << " (every finished cell of every run into " << options.out.string() << ")\n";
}

}  // namespace ccd::harness
