#include "harness/queries/command.hpp"

#include "core/error.hpp"
#include "datasets/atomic_file.hpp"
#include "harness/progress.hpp"
#include "harness/queries/answer_files.hpp"
#include "harness/queries/scoring.hpp"
#include "harness/queries/stress.hpp"
#include "harness/run/provenance.hpp"
#include "harness/table.hpp"
#include "harness/work_queue.hpp"
#include "strategies/plugin/plugin_narrow_phase.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>

namespace ccd::harness {

namespace {

/// Outputs are checked before any work and before any plugin is loaded; then unknown names fail, answer files once
/// they are matched to the queries.
void check_query_outputs(const QueriesOptions& options, const std::vector<std::string>& methods) {
  if (rank_info().rank == 0) {  // only rank 0 writes
    if (options.json) datasets::require_writable_file(*options.json);
    if (options.report) datasets::require_writable_directory(*options.report);
    if (options.write_answers) datasets::require_writable_file(*options.write_answers);
    // Where faults would go, when a method can have some (code or answers from outside ccdbench): made only when
    // there are faults, but it must be possible to make it.
    const bool from_outside = std::any_of(methods.begin(), methods.end(), [&](const std::string& method) {
      return names_answers(method) || method.find(std::string(narrowphase::kPluginHead) + ":") != std::string::npos;
    });
    if (from_outside) datasets::require_creatable_directory(options.faults);
  }
  for (const std::string& method : methods) {
    if (!names_answers(method)) make_query_method(method);
  }
}

/// The query files to score, answer files matched to them; unlabelled files refused unless allowed.
std::vector<datasets::QueryFile> load_query_files(const QueriesOptions& options, std::vector<std::string>& methods) {
  std::vector<datasets::QueryFile> files;
  for (const auto& path : datasets::discover_query_files(options.paths)) files.push_back(datasets::read_query_file(path));
  if (options.extremes) {
    for (datasets::QueryFile& file : extremes_query_files(datasets::extremes_suite())) files.push_back(std::move(file));
  }
  if (files.empty()) throw InputError({}, {}, "no query files found under the given paths");
  if (std::any_of(methods.begin(), methods.end(), names_answers) && options.scale_exponent != 0) {
    throw InputError("command line", "--scale-exponent", "answer files answer the queries as written: they cannot be scaled");
  }
  // Answer files are matched to the queries before any work: one that does not answer exactly these is refused.
  bind_answer_files(methods, files);
  for (const datasets::QueryFile& file : files) {
    const std::size_t unlabelled = file.queries.size() - file.labelled();
    if (unlabelled > 0 && !options.allow_unlabelled) {
      throw InputError(file.path, {},
                       std::to_string(unlabelled) + " of " + std::to_string(file.queries.size()) +
                           " queries have no truth label (no 7th column, no mma_bool/NAME_mma_bool.json): "
                           "their misses cannot be counted; --allow-unlabelled scores them with FN and "
                           "FP shown as '-'");
    }
  }
  return files;
}

/// δ as the queries are scored: scaled with them by 2^K, rounded up where it loses bits (a larger δ only adds
/// contacts).
double scaled_thickness(const QueriesOptions& options) {
  if (options.scale_exponent == 0) return options.thickness;
  double thickness = std::ldexp(options.thickness, options.scale_exponent);
  if (!std::isfinite(thickness))
    throw InputError("command line", "--thickness", "δ times 2^" + std::to_string(options.scale_exponent) + " overflows");
  if (std::ldexp(thickness, -options.scale_exponent) < options.thickness) thickness = std::nextafter(thickness, INFINITY);
  return thickness;
}

/// Under MPI, one work item per file (harness/work_queue.hpp): every rank has read the files; each scales and scores
/// the ones it is handed, and rank 0 puts the scores back in file order. nullopt on the other ranks.
std::optional<std::vector<QueryScore>> score_over_ranks(const std::vector<datasets::QueryFile>& files, const QueryScoringRequest& request,
                                                        int scale_exponent, std::size_t& left_out) {
  std::optional<QueryMethods> methods;  // made once a rank, for every file it is handed (a plugin's child starts once)
  const WorkFunction work = [&](const std::string& payload) {
    std::vector<datasets::QueryFile> one{files.at(std::stoull(payload))};
    const std::size_t left = scale_exponent != 0 ? scale_query_files(one, scale_exponent) : 0;
    nlohmann::json message = {{"left_out", left}, {"scores", nlohmann::json::array()}};
    if (!methods) methods = make_query_methods(request.methods);
    for (const QueryScore& score : score_query_file(one.front(), request, *methods)) message["scores"].push_back(score);
    return message.dump();
  };
  if (rank_info().rank != 0) {
    distribute({}, work, {});
    return std::nullopt;
  }
  std::vector<WorkItem> items;
  for (std::size_t i = 0; i < files.size(); ++i) items.push_back({std::to_string(i), {}});
  std::vector<nlohmann::json> results(files.size());
  Progress progress("queries: files", files.size());
  std::size_t finished = 0;
  distribute(items, work, [&](std::size_t index, const std::string& result, int) {
    results[index] = nlohmann::json::parse(result);
    progress.update(++finished);
  });
  std::vector<QueryScore> scores;
  for (const nlohmann::json& result : results) {
    left_out += result.at("left_out").get<std::size_t>();
    for (const nlohmann::json& score : result.at("scores")) scores.push_back(score.get<QueryScore>());
  }
  append_query_totals(scores, request.methods);
  return scores;
}

/// The table, the notes, and what the options ask written.
void report_query_scores(const std::vector<QueryScore>& scores, const std::vector<datasets::QueryFile>& files, const QueriesOptions& options,
                         std::ostream& out) {
  print_query_scores(scores, out);
  // Under MPI the files were scaled by the ranks that scored them: the copies written are scaled alike.
  write_query_faults(scores, files, options.faults, rank_info().size > 1 ? options.scale_exponent : 0, out);
  if (options.write_answers) {
    write_query_answers(*options.write_answers, scores);
    out << "answers: " << options.write_answers->string() << "\n";
  }
  if (const QueryScore& total = scores.back(); total.unlabelled > 0) {
    out << "note: " << total.unlabelled << " of " << total.queries
        << " queries had no truth label: FN and FP count the labelled ones only ('-': none labelled).\n";
  }
  // Labels are for thickness 0 unless a file says another (docs/DESIGN.md §7): scored at another δ, a method may
  // rightly answer otherwise than a label.
  const double scored = scaled_thickness(options);
  std::map<double, std::size_t> other;
  for (const datasets::QueryFile& file : files) other[file.labels_thickness] += file.labels_thickness != scored && file.labelled() > 0 ? 1 : 0;
  for (const auto& [labels, count] : other) {
    if (count == 0) continue;
    out << "note: the labels of " << count << " file" << (count == 1 ? " are" : "s are") << " for thickness " << labels << ", scored at " << scored
        << ": a method may rightly report " << (scored > labels ? "more (counted as FP here), never fewer" : "fewer (counted as FN here), never more")
        << ".\n";
  }
  if (options.json) {
    nlohmann::json rows = nlohmann::json::array();
    // Every record says where and how it was made, as run's do.
    const nlohmann::json made = environment();
    for (const QueryScore& score : scores) {
      rows.push_back(score_row(score));
      rows.back().update(made);
    }
    datasets::write_json_file(*options.json, rows);
  }
  if (options.report) {
    write_query_report(*options.report, scores, options.command_line);
    out << "report: " << (*options.report / "README.md").string() << "\n";
  }
}

}  // namespace

int run_queries(const QueriesOptions& options, std::ostream& out) {
  std::vector<std::string> methods = options.sweep ? sweep_methods(options.methods) : options.methods;
  check_query_outputs(options, methods);
  std::vector<datasets::QueryFile> files = load_query_files(options, methods);
  const double thickness = scaled_thickness(options);
  const QueryScoringRequest request{methods, thickness, options.repeats, options.toi, options.write_answers.has_value()};
  std::size_t left_out = 0;
  std::vector<QueryScore> scores;
  if (rank_info().size == 1) {
    if (options.scale_exponent != 0) left_out = scale_query_files(files, options.scale_exponent);
  } else {
    std::optional<std::vector<QueryScore>> gathered = score_over_ranks(files, request, options.scale_exponent, left_out);
    if (!gathered) return 0;
    scores = std::move(*gathered);
  }
  if (options.scale_exponent != 0) {
    out << "scaled every query by 2^" << options.scale_exponent << " (δ " << thickness << ")";
    if (left_out > 0) out << "; " << left_out << " queries left out: a coordinate overflows at this scale";
    out << "\n";
  }
  if (rank_info().size == 1) {
    Progress progress("queries: files", files.size());
    // Progress within a file too, a batch at a time (a file with hangs moved only when it was done).
    scores = score_query_files(files, request, [&](double done, std::size_t total) {
      progress.update(done, total, files[std::min(static_cast<std::size_t>(done), total - 1)].path.filename().string());
    });
  }
  report_query_scores(scores, files, options, out);
  return 0;
}

}  // namespace ccd::harness
