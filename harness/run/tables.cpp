#include "harness/run/tables.hpp"

#include "datasets/atomic_file.hpp"
#include "harness/run/provenance.hpp"
#include "strategies/registry.hpp"

#include <algorithm>
#include <ostream>

namespace ccd::harness {
namespace {

using nlohmann::json;

constexpr const char* kTrianglePairMark = " (†)";
constexpr const char* kTrianglePairNote =
    "(†) judged by triangle pairs at δ = 0 (DESIGN.md §3): a truth pair counts as found when a reported triangle pair "
    "contains both its primitives; false alarms are reported triangle pairs that contain no colliding pair.\n";
constexpr std::size_t kStrategyColumn = 3;

/// The cell whose time `s` is compared with: its strategy's baseline on the same scene, with the same narrow phase
/// (any, for a strategy with elementary tests of its own), measured in this invocation on the same rank and machine
/// (MPI spreads cells over ranks and hosts). nullptr when there is none.
const json* baseline_of(const json& s, const std::vector<json>& summaries) {
  if (s.value("resumed", false)) return nullptr;
  const strategies::StrategySpec spec = strategies::strategy_names_of(s["strategy"]);
  const std::string& baseline = strategies::find_strategy(spec.name).baseline;
  for (const json& other : summaries) {
    if (other.value("resumed", false) || other["scene"] != s["scene"]) continue;
    if (other.value("rank", 0) != s.value("rank", 0) || other.value("machine", "") != s.value("machine", "")) continue;
    const strategies::StrategySpec candidate = strategies::strategy_names_of(other["strategy"]);
    if (candidate.name != baseline) continue;
    if (!spec.narrow_phase.empty() && candidate.narrow_phase != spec.narrow_phase) continue;
    return &other;
  }
  return nullptr;
}

}  // namespace

Table summary_table(const std::vector<json>& summaries) {
  using Align = Table::Align;
  Table table({{"scene"}, {"triangles", Align::right}, {"steps", Align::right}, {"strategy"}, {"ms/step", Align::right},
               {"stages (ms)"}, {"vs full", Align::right}, {"candidates/step", Align::right}, {"tests/step", Align::right},
               {"colliding", Align::right}, {"missed (culled/tested)", Align::right}, {"false alarms", Align::right}});
  const bool with_toi = std::any_of(summaries.begin(), summaries.end(), [](const json& s) { return s.contains("toi_late"); });
  for (const json& s : summaries) {
    std::string speedup = "-";
    if (const json* base = baseline_of(s, summaries); base && s["ms_per_step"].get<double>() > 0) {
      speedup = fixed((*base)["ms_per_step"].get<double>() / s["ms_per_step"].get<double>(), 2) + "x";
    }
    std::string stages;
    for (const auto& [stage, ms] : s["stage_ms"].items()) stages += (stages.empty() ? "" : ", ") + stage + " " + fixed(ms.get<double>(), 2);
    const bool verified = s.value("verified", false);
    auto count = [&](const char* field) { return verified ? std::to_string(s[field].get<std::size_t>()) : std::string("-"); };
    table.add_row({s["scene"].get<std::string>() + (s.value("resumed", false) ? " (resumed)" : ""),
                   std::to_string(s["triangles"].get<std::size_t>()), std::to_string(s["steps"].get<std::size_t>()),
                   s["strategy"].get<std::string>() + (s.value("judged_by", "") == "triangle pairs" ? kTrianglePairMark : ""),
                   fixed(s["ms_per_step"].get<double>(), 3), stages, speedup, fixed(s["candidate_pairs"].get<double>(), 0),
                   fixed(s["elementary_tests"].get<double>(), 0), count("colliding"),
                   verified ? count("missed") + " (" + count("missed_culled") + "/" + count("missed_tested") + ")" : "-",
                   count("false_alarms")});
  }
  if (with_toi) {
    table.add_column({"TOI late (error max / mean)", Align::right});
    for (std::size_t r = 0; r < summaries.size(); ++r) {
      const json& s = summaries[r];
      if (!s.contains("toi_late")) continue;
      std::vector<std::string> cells = table.row(r);
      cells.back() = std::to_string(s["toi_late"].get<std::size_t>()) + " of " + std::to_string(s["toi_checked"].get<std::size_t>()) + " (" +
                     significant(s["toi_error_max"].get<double>(), 3) + " / " + significant(s["toi_error_mean"].get<double>(), 3) + ")";
      table.set_row(r, std::move(cells));
    }
  }
  return table;
}

std::string summary_notes(const Table& table) {
  for (std::size_t r = 0; r < table.rows(); ++r) {
    if (table.row(r)[kStrategyColumn].find(kTrianglePairMark) != std::string::npos) return kTrianglePairNote;
  }
  return "";
}

void write_report(const std::filesystem::path& directory, const Table& table, const std::vector<json>& cells, const std::string& command) {
  json steps = json::array();
  for (const json& cell : cells) {
    for (const json& step : cell["steps"]) steps.push_back(step);
  }
  datasets::write_json_file(directory / "steps.json", steps);
  datasets::AtomicFile file(directory / "README.md", std::ios::out);
  std::ostream& out = file.stream();
  out << "# ccdbench run\n\nEvery number below comes from one invocation (speed-ups only between cells of this run):\n\n```sh\n"
      << command << "\n```\n\n";
  table.print_markdown(out);
  out << '\n' << summary_notes(table);
  const json env = environment();
  out << "\nMachine: " << env["machine"].get<std::string>() << "; build " << env["build_type"].get<std::string>() << ", "
      << env["threads"] << " threads, revision " << env["git_revision"].get<std::string>() << ".\n\n"
      << "![ms per step over the steps](ms_per_step.png)\n\n![stage breakdown per strategy](stages.png)\n\n"
      << "Plots drawn by `scripts/plot_run.py` from `steps.json`.\n";
  file.commit();
}

}  // namespace ccd::harness
