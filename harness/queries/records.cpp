// QueryScore as records leave the process: its one serializer (to_json, from_json: what ranks exchange), the
// table, the answer file --write-answers writes, and the report page. Scoring itself is scoring.cpp's.
#include "datasets/atomic_file.hpp"
#include "datasets/content_hash.hpp"
#include "datasets/rational.hpp"
#include "harness/cell_store.hpp"
#include "harness/queries/answer_files.hpp"
#include "harness/queries/scoring.hpp"
#include "harness/statistics.hpp"
#include "harness/table.hpp"
#include "strategies/plugin/plugin_narrow_phase.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iomanip>
#include <map>
#include <ostream>
#include <sstream>

namespace ccd::harness {

namespace {

std::string labelled_text(const QueryScore& s, std::size_t count) { return s.any_labelled() ? std::to_string(count) : "-"; }

/// NaN is not JSON: null stands for it in messages.
nlohmann::json number_list(const std::vector<double>& values) {
  nlohmann::json list = nlohmann::json::array();
  for (double v : values) list.push_back(std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v));
  return list;
}
std::vector<double> numbers_of(const nlohmann::json& list) {
  std::vector<double> values;
  for (const nlohmann::json& v : list) values.push_back(v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>());
  return values;
}
nlohmann::json label_list(const QueryScore& s) {
  nlohmann::json list = nlohmann::json::array();
  for (const std::optional<bool>& label : s.labels) list.push_back(label ? nlohmann::json(*label) : nlohmann::json(nullptr));
  return list;
}
nlohmann::json answer_list(const QueryScore& s) {
  nlohmann::json list = nlohmann::json::array();
  for (const QueryAnswer& a : s.answers) {
    list.push_back({a.collides, std::isnan(a.toi) ? nlohmann::json(nullptr) : nlohmann::json(a.toi), a.fault});
  }
  return list;
}

}  // namespace

void to_json(nlohmann::json& j, const QueryScore::ErrorQuery& e) { j = {{"index", e.index}, {"line", e.line}, {"message", e.message}}; }

void from_json(const nlohmann::json& j, QueryScore::ErrorQuery& e) {
  e.index = j.at("index").get<std::size_t>();
  e.line = j.at("line").get<std::size_t>();
  e.message = j.at("message").get<std::string>();
}

void to_json(nlohmann::json& j, const QueryScore& s) {
  j = {{"method", s.method},
       {"file", s.file},
       {"thickness", s.thickness},
       {"queries", s.queries},
       {"positives", s.positives},
       {"reported", s.reported},
       {"false_negatives", s.false_negatives},
       {"false_positives", s.false_positives},
       {"unlabelled", s.unlabelled},
       {"ns_per_query", s.ns_per_query},
       {"with_toi", s.with_toi},
       {"toi_checked", s.toi_checked},
       {"toi_late", s.toi_late},
       {"toi_error_max", s.toi_error_max},
       {"toi_error_sum", s.toi_error_sum},
       {"toi_errors", s.toi_errors},
       {"false_negative_lines", s.false_negative_lines},
       {"errors", s.errors},
       {"changed_between_passes", s.changed_between_passes},
       {"error_queries", s.error_queries},
       {"answers", answer_list(s)},
       {"exact_toi", number_list(s.exact_toi)},
       {"labels", label_list(s)}};
}

void from_json(const nlohmann::json& m, QueryScore& s) {
  s = QueryScore();
  s.method = m.at("method");
  s.file = m.at("file");
  s.thickness = m.at("thickness");
  s.queries = m.at("queries");
  s.positives = m.at("positives");
  s.reported = m.at("reported");
  s.false_negatives = m.at("false_negatives");
  s.false_positives = m.at("false_positives");
  s.unlabelled = m.at("unlabelled");
  s.ns_per_query = m.at("ns_per_query");
  s.with_toi = m.at("with_toi");
  s.toi_checked = m.at("toi_checked");
  s.toi_late = m.at("toi_late");
  s.toi_error_max = m.at("toi_error_max");
  s.toi_error_sum = m.at("toi_error_sum");
  s.toi_errors = m.at("toi_errors").get<std::vector<double>>();
  s.false_negative_lines = m.at("false_negative_lines").get<std::vector<std::size_t>>();
  s.errors = m.at("errors");
  s.changed_between_passes = m.at("changed_between_passes");
  s.error_queries = m.at("error_queries").get<std::vector<QueryScore::ErrorQuery>>();
  for (const nlohmann::json& a : m.at("answers")) {
    s.answers.push_back(
        {a.at(0).get<bool>(), a.at(1).is_null() ? std::numeric_limits<double>::quiet_NaN() : a.at(1).get<double>(), a.at(2).get<std::string>()});
  }
  s.exact_toi = numbers_of(m.at("exact_toi"));
  for (const nlohmann::json& label : m.at("labels")) s.labels.push_back(label.is_null() ? std::nullopt : std::optional<bool>(label.get<bool>()));
}

namespace {

/// The scores as a table: text on a terminal, Markdown in a report.
Table query_table(const std::vector<QueryScore>& scores, bool markdown) {
  using Align = Table::Align;
  Table table({{"method"},
               {"file"},
               {"queries", Align::right},
               {"positives", Align::right},
               {"reported", Align::right},
               {"FN", Align::right},
               {"FP", Align::right},
               {"ns/query", Align::right}});
  const bool with_toi = !scores.empty() && scores.front().with_toi;
  // An error is its own outcome (a method that gave no answer): a column wherever a method can give one.
  const bool with_errors = std::any_of(scores.begin(), scores.end(),
                                       [](const QueryScore& s) { return s.errors > 0 || plugin::names_plugin(s.method) || names_answers(s.method); });
  if (with_errors) table.add_column({"errors", Align::right});
  const bool with_changes = std::any_of(scores.begin(), scores.end(), [](const QueryScore& s) { return s.changed_between_passes > 0; });
  if (with_changes) table.add_column({"changed between passes", Align::right});
  if (with_toi) {
    for (const char* header : {"TOI late", "TOI error mean", "median", "p99", "max"}) table.add_column({header, Align::right});
  }
  for (const QueryScore& s : scores) {
    std::vector<std::string> row = {markdown ? "`" + s.method + "`" : s.method,
                                    s.file,
                                    std::to_string(s.queries),
                                    labelled_text(s, s.positives),
                                    std::to_string(s.reported),
                                    labelled_text(s, s.false_negatives),
                                    labelled_text(s, s.false_positives),
                                    fixed(s.ns_per_query, 0)};
    if (with_errors) row.push_back(std::to_string(s.errors));
    if (with_changes) row.push_back(std::to_string(s.changed_between_passes));
    const std::optional<ToiErrors> errors = toi_errors_of(s);
    if (with_toi && !errors) {
      // Nothing checked (no TOI reported on a colliding query): '-', never a 0 nobody measured.
      for (int k = 0; k < 5; ++k) row.push_back("-");
    } else if (with_toi) {
      row.push_back(std::to_string(s.toi_late));
      for (double value : {errors->mean, errors->median, errors->p99, errors->max}) row.push_back(significant(value, 3));
    }
    table.add_row(std::move(row));
  }
  return table;
}

}  // namespace

void print_query_scores(const std::vector<QueryScore>& scores, std::ostream& out) { query_table(scores, false).print(out); }

void write_query_answers(const std::filesystem::path& path, const std::vector<QueryScore>& scores) {
  // Per file, per query, per method, in the order scored; the label and exact TOI once per query and method.
  std::map<std::string, std::vector<const QueryScore*>> by_file;
  std::vector<std::string> file_order;
  for (const QueryScore& score : scores) {
    if (score.file == "(all)") continue;
    if (!by_file.count(score.file)) file_order.push_back(score.file);
    by_file[score.file].push_back(&score);
  }
  datasets::AtomicFile file(path, std::ios::out);
  std::ostream& out = file.stream();
  out << "file,index,method,hit,toi,label,exact_toi\n";
  for (const std::string& name : file_order) {
    const std::vector<const QueryScore*>& of_file = by_file[name];
    const std::size_t count = of_file.front()->answers.size();
    for (std::size_t q = 0; q < count; ++q) {
      for (const QueryScore* score : of_file) {
        const QueryAnswer& a = score->answers.at(q);
        const double exact = score->exact_toi.at(q);
        const std::optional<bool>& label = score->labels.at(q);
        out << name << ',' << q << ',' << score->method << ','
            << (!a.fault.empty() ? "error"
                : a.collides     ? "1"
                                 : "0")
            << ',' << (a.collides && !std::isnan(a.toi) ? answer_number(a.toi) : "") << ',' << (label ? (*label ? "1" : "0") : "") << ','
            << (std::isnan(exact) ? "" : answer_number(exact)) << '\n';
      }
    }
  }
  file.commit();
}

void write_query_faults(const std::vector<QueryScore>& scores, const std::vector<datasets::QueryFile>& files, const std::filesystem::path& faults,
                        int scale_exponent, std::ostream& out) {
  std::map<std::filesystem::path, std::string> notes_of_folder;
  for (const QueryScore& score : scores) {
    if (score.file == "(all)" || score.error_queries.empty()) continue;
    const auto file = std::find_if(files.begin(), files.end(), [&](const datasets::QueryFile& f) { return f.path.string() == score.file; });
    if (file == files.end()) continue;
    // A method's folder: its name's start and a hash of the whole (two specs that differ late never share one).
    datasets::ContentHash method_hash;
    method_hash.text(score.method);
    const std::filesystem::path folder = faults / (safe_path_component(score.method.substr(0, 100)) + "-" + method_hash.hex().substr(0, 8));
    std::vector<datasets::QueryFile> kept(1);
    kept[0].kind = file->kind;
    kept[0].labels_thickness = file->labels_thickness;
    std::string notes;
    for (const QueryScore::ErrorQuery& fault : score.error_queries) {
      kept[0].queries.push_back(file->queries.at(fault.index));
      notes += score.file + " query " + std::to_string(fault.index + 1) + " (index " + std::to_string(fault.index) + ", line " +
               std::to_string(fault.line) + "; query " + std::to_string(kept[0].queries.size()) + " of WRITTEN): " + fault.message + "\n";
    }
    if (scale_exponent != 0) scale_query_files(kept, scale_exponent);
    datasets::ContentHash path_hash;
    path_hash.text(file->path.string());
    const std::filesystem::path written =
        folder / std::string(datasets::to_string(file->kind)) / (file->path.stem().string() + "-" + path_hash.hex().substr(0, 8) + ".csv");
    datasets::write_query_file(written, kept[0].queries, kept[0].labels_thickness);
    // The command that scores them again, as printed: the method as it ran, at the δ it was scored at.
    char thickness[64];
    const std::string replay = "ccdbench queries " + written.string() + " --method " + score.method + " --thickness " +
                               std::string(thickness, std::to_chars(thickness, thickness + sizeof thickness, score.thickness).ptr) +
                               (kept[0].has_truth() ? "" : " --allow-unlabelled");
    for (std::size_t at = notes.find("WRITTEN"); at != std::string::npos; at = notes.find("WRITTEN", at)) {
      notes.replace(at, 7, written.string());
      at += written.string().size();
    }
    notes_of_folder[folder] += notes + "  replay: " + replay + "\n";
    out << score.method << ": " << score.errors << " of " << score.queries << " queries of " << score.file << " got no answer; first: query "
        << score.error_queries.front().index + 1 << " (line " << score.error_queries.front().line << "): " << score.error_queries.front().message
        << "\n  written to " << written.string() << " (replay: " << replay << ")\n";
  }
  for (const auto& [folder, notes] : notes_of_folder) {
    datasets::AtomicFile list(folder / "FAULTS.txt", std::ios::out);
    list.stream() << notes;
    list.commit();
  }
}

void write_query_report(const std::filesystem::path& directory, const std::vector<QueryScore>& scores, const std::string& command) {
  nlohmann::json rows = nlohmann::json::array();
  for (const QueryScore& score : scores) rows.push_back(score_row(score));
  datasets::write_json_file(directory / "scores.json", rows);
  datasets::AtomicFile file(directory / "README.md", std::ios::out);
  std::ostream& out = file.stream();
  out << "# Narrow phases: time per query against misses and false alarms\n\n"
      << "Every method on the same queries, in one run. ns/query is the median over the repeats of each file's time\n"
      << "divided by its queries; FN are missed collisions (truth positive, answer no), FP false alarms. Narrow phases\n"
      << "get the doubles the query's rationals round to; `exact` is the reference on the rationals. The truth labels are\n"
      << "for zero thickness. Reproduce every number with:\n\n```sh\n"
      << command << "\n```\n\n";
  query_table(scores, true).print_markdown(out);
  out << "\nThe trade, per variant over all files (`(all)` rows), can be drawn with `/usr/bin/python3 "
         "scripts/plot_narrowphase.py scores.json tradeoff.png` (`scripts/narrowphase-report.sh` does).\n";
  file.commit();
}

}  // namespace ccd::harness
