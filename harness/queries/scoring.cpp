#include "harness/queries/scoring.hpp"

#include "ccd/config.hpp"
#include "datasets/atomic_file.hpp"
#include "datasets/rational.hpp"
#include "harness/queries/answer_files.hpp"
#include "harness/statistics.hpp"
#include "harness/table.hpp"
#include "harness/timed_region.hpp"
#include "reference/elementary_pair.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "strategies/registry.hpp"

#include <nlohmann/json.hpp>

#include "strategies/plugin/call_guard.hpp"
#include "strategies/plugin/library.hpp"
#include "strategies/plugin/plugin_narrow_phase.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <map>
#include <ostream>
#include <stdexcept>

namespace ccd::harness {
namespace {

/// How many answers of `again` differ from `first`'s: outcome, TOI bits, or whether it was an error.
std::size_t changed_answers(const std::vector<QueryAnswer>& again, const std::vector<QueryAnswer>& first) {
  std::size_t changed = 0;
  for (std::size_t q = 0; q < again.size(); ++q) {
    const QueryAnswer& a = again[q];
    const QueryAnswer& b = first[q];
    const bool same_toi = (std::isnan(a.toi) && std::isnan(b.toi)) || std::memcmp(&a.toi, &b.toi, sizeof a.toi) == 0;
    if (a.collides != b.collides || !same_toi || a.fault.empty() != b.fault.empty()) ++changed;
  }
  return changed;
}

/// A value or null (unknown).
template <class T>
nlohmann::json or_null(const std::optional<T>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

}  // namespace

std::optional<ToiErrors> toi_errors_of(const QueryScore& s) {
  if (!s.with_toi || s.toi_checked == 0) return std::nullopt;
  return ToiErrors{s.toi_error_max, s.toi_error_sum / static_cast<double>(s.toi_checked), percentile(s.toi_errors, 50), percentile(s.toi_errors, 99)};
}

nlohmann::json score_row(const QueryScore& s) {
  nlohmann::json row = {{"method", s.method},
                        {"file", s.file},
                        {"thickness", s.thickness},
                        {"queries", s.queries},
                        {"positives", or_null(s.labelled(s.positives))},
                        {"reported", s.reported},
                        {"false_negatives", or_null(s.labelled(s.false_negatives))},
                        {"false_positives", or_null(s.labelled(s.false_positives))},
                        {"unlabelled", s.unlabelled},
                        {"ns_per_query", s.ns_per_query},
                        {"false_negative_lines", s.false_negative_lines},
                        {"errors", s.errors},
                        {"changed_between_passes", s.changed_between_passes}};
  if (!s.error_queries.empty()) row["error_queries"] = s.error_queries;
  if (s.with_toi) {
    const std::optional<ToiErrors> errors = toi_errors_of(s);
    row["toi_checked"] = s.toi_checked;
    row["toi_late"] = s.toi_late;
    row["toi_error_max"] = errors ? nlohmann::json(errors->max) : nlohmann::json(nullptr);
    row["toi_error_mean"] = errors ? nlohmann::json(errors->mean) : nlohmann::json(nullptr);
    row["toi_error_median"] = errors ? nlohmann::json(errors->median) : nlohmann::json(nullptr);
    row["toi_error_p99"] = errors ? nlohmann::json(errors->p99) : nlohmann::json(nullptr);
  }
  return row;
}

std::vector<QueryScore> score_query_file(const datasets::QueryFile& file, const QueryScoringRequest& request) {
  return score_query_file(file, request, make_query_methods(request.methods));
}

std::vector<QueryScore> score_query_file(const datasets::QueryFile& file, const QueryScoringRequest& request, const QueryMethods& methods,
                                         const std::function<void(double)>& moved) {
  std::vector<QueryScore> scores;
  // Exact TOI floors, once per file for every method, outside the timed passes: of the doubles the narrow phases
  // are given (for a query that is not exactly doubles, its rationals are another question).
  std::vector<double> exact_toi(file.queries.size(), std::numeric_limits<double>::quiet_NaN());
  if (request.toi || request.keep_answers) {
    for (std::size_t q = 0; q < file.queries.size(); ++q) {
      if (file.queries[q].truth == false) continue;
      const reference::Decision decision = reference::decide(reference_kind(file.kind), file.queries[q].rounded, request.thickness, {true, true, 64});
      if (decision.toi_floor) exact_toi[q] = *decision.toi_floor;
    }
  }
  const double passes = static_cast<double>(methods.size()) * std::max(1, request.repeats);
  double passes_done = 0;
  for (const auto& method : methods) {
    QueryScore score;
    score.method = method->name();
    score.file = file.path.string();
    score.thickness = request.thickness;
    score.with_toi = request.toi;
    std::vector<double> per_query;
    std::vector<QueryAnswer> first_answers;
    // What a plugin that ends the process was doing: this file, and (per query, one relaxed store) which query.
    plugin::set_activity("file " + file.path.string() + " (method " + score.method + ")", "query");
    for (int repeat = 0; repeat < std::max(1, request.repeats); ++repeat) {
      std::vector<QueryAnswer> answers;
      const auto start = std::chrono::steady_clock::now();
      const auto answered = [&](std::size_t count) {
        if (moved) moved((passes_done + static_cast<double>(count) / static_cast<double>(std::max<std::size_t>(1, file.queries.size()))) / passes);
      };
      {
        const TimedRegion timed;
        answers = method->answer_all(file, request.thickness, moved ? answered : std::function<void(std::size_t)>());
      }
      ++passes_done;
      const std::chrono::duration<double, std::nano> elapsed = std::chrono::steady_clock::now() - start;
      per_query.push_back(file.queries.empty() ? 0.0 : elapsed.count() / static_cast<double>(file.queries.size()));
      if (repeat > 0) {
        // Later passes only time, and say whether an answer changed (verdicts are the first pass's).
        harness_pass("query scoring");
        score.changed_between_passes += changed_answers(answers, first_answers);
        continue;
      }
      first_answers = answers;
      harness_pass("query scoring");
      for (std::size_t q = 0; q < file.queries.size(); ++q) {
        const datasets::Query& query = file.queries[q];
        const bool reported = answers[q].collides;
        if (!answers[q].fault.empty()) {
          score.errors += 1;
          if (score.error_queries.size() < kKeptQueryFaults) score.error_queries.push_back({q, query.first_line, answers[q].fault});
        }
        // Lateness is exact: exact_toi is the largest double not after the earliest contact.
        if (request.toi && reported && !std::isnan(exact_toi[q]) && !std::isnan(answers[q].toi)) {
          const double error = std::abs(answers[q].toi - exact_toi[q]);
          score.toi_checked += 1;
          score.toi_late += answers[q].toi > exact_toi[q] ? 1 : 0;
          score.toi_error_max = std::max(score.toi_error_max, error);
          score.toi_error_sum += error;
          score.toi_errors.push_back(error);
        }
        score.queries += 1;
        score.reported += reported ? 1 : 0;
        if (!query.truth) {
          score.unlabelled += 1;
          continue;
        }
        score.positives += *query.truth ? 1 : 0;
        if (*query.truth && !reported) {
          score.false_negatives += 1;
          if (score.false_negative_lines.size() < 20) score.false_negative_lines.push_back(query.first_line);
        }
        if (!*query.truth && reported) score.false_positives += 1;
      }
      if (request.keep_answers) {
        score.answers = std::move(answers);
        score.exact_toi = exact_toi;
        for (const datasets::Query& query : file.queries) score.labels.push_back(query.truth);
      }
    }
    // As run audits a cell with misses: a plugin that missed, asked once, answers the file again (untimed), and
    // answers that changed are counted (it answers by what it was asked before, or another reply was taken for one).
    if (request.repeats <= 1 && score.false_negatives > 0 && plugin::names_plugin(score.method)) {
      score.changed_between_passes += changed_answers(method->answer_all(file, request.thickness), first_answers);
    }
    score.ns_per_query = median(per_query);
    scores.push_back(std::move(score));
  }
  plugin::set_activity({});
  return scores;
}

void append_query_totals(std::vector<QueryScore>& scores, const std::vector<std::string>& methods) {
  std::map<std::string, QueryScore> totals;
  std::map<std::string, double> total_nanoseconds;
  for (const QueryScore& score : scores) {
    QueryScore& total = totals[score.method];
    total.method = score.method;
    total.file = "(all)";
    total.thickness = score.thickness;
    total.queries += score.queries;
    total.positives += score.positives;
    total.reported += score.reported;
    total.false_negatives += score.false_negatives;
    total.false_positives += score.false_positives;
    total.unlabelled += score.unlabelled;
    total.with_toi = score.with_toi;
    total.toi_checked += score.toi_checked;
    total.toi_late += score.toi_late;
    total.toi_error_max = std::max(total.toi_error_max, score.toi_error_max);
    total.toi_error_sum += score.toi_error_sum;
    total.toi_errors.insert(total.toi_errors.end(), score.toi_errors.begin(), score.toi_errors.end());
    total.errors += score.errors;
    total.changed_between_passes += score.changed_between_passes;
    total_nanoseconds[score.method] += score.ns_per_query * static_cast<double>(score.queries);
  }
  // Per-file scores come in the order of `methods` for each file: the first file's name each method (resolved),
  // without making any again (an isolated plugin would start a child for its name).
  for (std::size_t k = 0; k < methods.size(); ++k) {
    const std::string method = k < scores.size() ? scores[k].method : make_query_method(methods[k])->name();
    QueryScore total = totals[method];
    total.method = method;
    total.file = "(all)";
    total.ns_per_query = total.queries == 0 ? 0.0 : total_nanoseconds[method] / static_cast<double>(total.queries);
    scores.push_back(std::move(total));
  }
}

std::vector<QueryScore> score_query_files(const std::vector<datasets::QueryFile>& files, const QueryScoringRequest& request,
                                          const std::function<void(double, std::size_t)>& moved) {
  const QueryMethods methods = make_query_methods(request.methods);
  std::vector<QueryScore> scores;
  for (std::size_t index = 0; index < files.size(); ++index) {
    const auto within = [&](double fraction) { moved(static_cast<double>(index) + fraction, files.size()); };
    for (QueryScore& score : score_query_file(files[index], request, methods, moved ? within : std::function<void(double)>())) {
      scores.push_back(std::move(score));
    }
    if (moved) moved(static_cast<double>(index + 1), files.size());
  }
  append_query_totals(scores, request.methods);
  return scores;
}

std::size_t scale_query_files(std::vector<datasets::QueryFile>& files, int exponent) {
  std::size_t left_out = 0;
  for (datasets::QueryFile& file : files) {
    std::vector<datasets::Query> kept;
    for (datasets::Query& query : file.queries) {
      bool finite = true, exact = true;
      for (int r = 0; r < 8; ++r) {
        for (int k = 0; k < 3; ++k) {
          mpq_class& value = query.exact[r][k];
          if (exponent >= 0) {
            mpq_mul_2exp(value.get_mpq_t(), value.get_mpq_t(), static_cast<mp_bitcnt_t>(exponent));
          } else {
            mpq_div_2exp(value.get_mpq_t(), value.get_mpq_t(), static_cast<mp_bitcnt_t>(-exponent));
          }
          const datasets::RoundedRational rounded = datasets::round_to_double(value);
          finite = finite && std::isfinite(rounded.value);
          exact = exact && rounded.exact;
          query.rounded[r][k] = rounded.value;
        }
      }
      if (!finite) {
        ++left_out;
        continue;
      }
      if (query.exactly_double && !exact) {
        // The doubles are now another question than the rationals: ask that one, and label it exactly.
        for (int r = 0; r < 8; ++r) {
          for (int k = 0; k < 3; ++k) query.exact[r][k] = mpq_class(query.rounded[r][k]);
        }
        // Labels are for the file's labels thickness (0 unless it says another; docs/DESIGN.md §7), scaled with it.
        if (query.truth) query.truth = decide_query_exactly(query, file.kind, std::ldexp(file.labels_thickness, exponent), false).collides;
      } else {
        query.exactly_double = exact;
      }
      kept.push_back(std::move(query));
    }
    file.queries = std::move(kept);
    file.labels_thickness = std::ldexp(file.labels_thickness, exponent);
  }
  return left_out;
}

std::vector<std::string> sweep_methods(const std::vector<std::string>& methods) {
  std::vector<std::string> swept;
  for (const std::string& method : methods) {
    const std::string name = method.substr(0, method.find(':'));
    if (!narrowphase::is_narrow_phase(name) || narrowphase::find_narrow_phase(name).sweeps.empty()) {
      swept.push_back(method);
      continue;
    }
    // Each axis in turn, from the method as given (its other keys kept): the swept key's value replaces its own.
    for (const narrowphase::SweepAxis& axis : narrowphase::find_narrow_phase(name).sweeps) {
      std::string kept = name;
      std::size_t at = method.find(':');
      while (at != std::string::npos) {
        const std::size_t next = method.find(':', at + 1);
        const std::string part = method.substr(at + 1, next == std::string::npos ? std::string::npos : next - at - 1);
        if (part.substr(0, part.find('=')) != axis.key) kept += ":" + part;
        at = next;
      }
      for (const std::string& value : axis.values) swept.push_back(kept + ":" + axis.key + "=" + value);
    }
  }
  return swept;
}

}  // namespace ccd::harness
