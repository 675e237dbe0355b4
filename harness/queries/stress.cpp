#include "harness/queries/stress.hpp"

#include "harness/queries/scoring.hpp"
#include "harness/table.hpp"
#include "reference/elementary_pair.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "strategies/plugin/call_guard.hpp"

#include <nlohmann/json.hpp>

#include <map>
#include <ostream>

namespace ccd::harness {
nlohmann::json to_json(const StressRow& row) {
  return {{"family", row.family},
          {"method", row.method},
          {"thickness", row.thickness},
          {"queries", row.queries},
          {"positives", row.positives},
          {"false_negatives", row.false_negatives},
          {"false_positives", row.false_positives},
          {"errors", row.errors},
          {"missed", row.missed}};
}

std::vector<StressRow> run_stress(const std::vector<datasets::ExtremeQuery>& suite, const std::vector<std::string>& methods) {
  std::vector<std::unique_ptr<narrowphase::NarrowPhase>> variants;
  for (const std::string& spec : methods) variants.push_back(narrowphase::make_narrow_phase_from_spec(spec));
  std::vector<StressRow> rows;
  for (const char* pass : {"zero", "positive"}) {
    std::map<std::pair<std::string, std::string>, StressRow> by_family;  // (family, method)
    std::map<std::string, StressRow> totals;
    // Every case's δ and truth first; then each method on every case (in one batch where it prefers batches: an
    // isolated plugin), its answers tallied by family.
    std::vector<narrowphase::NarrowPhase::BatchPair> pairs;
    std::vector<bool> truths;
    for (const datasets::ExtremeQuery& query : suite) {
      const double thickness = std::string(pass) == "zero" ? 0.0 : query.positive_thickness;
      truths.push_back(reference::decide(reference_kind(query.kind), query.rows, thickness).collides);
      pairs.push_back({&query.rows, query.kind == datasets::QueryKind::vertex_face, thickness});
    }
    for (const auto& variant : variants) {
      std::vector<narrowphase::NarrowPhaseResult> answers(pairs.size());
      if (variant->prefers_batches()) {
        variant->answer_batch(pairs, answers);
      } else {
        for (std::size_t i = 0; i < pairs.size(); ++i) {
          plugin::set_activity("the extremes suite (stress), " + suite[i].family + ": " + suite[i].name + ", δ " + pass);
          answers[i] = pairs[i].vertex_face ? variant->vertex_face(*pairs[i].rows, pairs[i].thickness)
                                            : variant->edge_edge(*pairs[i].rows, pairs[i].thickness);
        }
      }
      for (std::size_t i = 0; i < pairs.size(); ++i) {
        const datasets::ExtremeQuery& query = suite[i];
        const bool truth = truths[i];
        const narrowphase::NarrowPhaseResult& answer = answers[i];
        for (StressRow* row : {&by_family[{query.family, variant->name()}], &totals[variant->name()]}) {
          row->family = row == &totals[variant->name()] ? "(all)" : query.family;
          row->method = variant->name();
          row->thickness = pass;
          row->queries += 1;
          row->positives += truth ? 1 : 0;
          if (truth && !answer.collides) {
            row->false_negatives += 1;
            if (row->missed.size() < 10) row->missed.push_back(query.family + ": " + query.name);
          }
          if (!truth && answer.collides) row->false_positives += 1;
          if (!answer.fault.empty()) row->errors += 1;
        }
      }
    }
    plugin::set_activity({});
    for (const std::string& family : datasets::extremes_families()) {
      for (const auto& variant : variants) {
        const auto it = by_family.find({family, variant->name()});
        if (it != by_family.end()) rows.push_back(it->second);
      }
    }
    for (const auto& variant : variants) rows.push_back(totals[variant->name()]);
  }
  return rows;
}

void print_stress(const std::vector<StressRow>& rows, std::ostream& out) {
  using Align = Table::Align;
  Table table({{"family"},
               {"method"},
               {"δ"},
               {"queries", Align::right},
               {"positive", Align::right},
               {"FN", Align::right},
               {"FP", Align::right},
               {"errors", Align::right}});
  for (const StressRow& row : rows) {
    table.add_row({row.family, row.method, row.thickness == "zero" ? "0" : "positive", std::to_string(row.queries), std::to_string(row.positives),
                   std::to_string(row.false_negatives), std::to_string(row.false_positives), std::to_string(row.errors)});
  }
  table.print(out);
}

std::vector<datasets::QueryFile> extremes_query_files(const std::vector<datasets::ExtremeQuery>& suite) {
  std::vector<datasets::QueryFile> files(2);
  files[0].path = "extremes-suite/vertex-face";
  files[0].kind = datasets::QueryKind::vertex_face;
  files[1].path = "extremes-suite/edge-edge";
  files[1].kind = datasets::QueryKind::edge_edge;
  for (const datasets::ExtremeQuery& extreme : suite) {
    datasets::Query query = datasets::query_of_doubles(extreme.rows);
    query.truth = reference::decide(reference_kind(extreme.kind), extreme.rows, 0.0).collides;
    files[extreme.kind == datasets::QueryKind::vertex_face ? 0 : 1].queries.push_back(std::move(query));
  }
  return files;
}

void write_extremes_queries(const std::vector<datasets::ExtremeQuery>& suite, const std::filesystem::path& directory) {
  const std::vector<datasets::QueryFile> files = extremes_query_files(suite);
  datasets::write_query_file(directory / "vertex-face" / "extremes.csv", files[0].queries);
  datasets::write_query_file(directory / "edge-edge" / "extremes.csv", files[1].queries);
}

}  // namespace ccd::harness
