#pragma once
/// @file
/// Scoring methods on query files (`ccdbench queries`): the same queries, every method, one run. The methods are
/// methods.hpp's.

#include "datasets/query_file.hpp"
#include "harness/queries/methods.hpp"

#include <nlohmann/json_fwd.hpp>

#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ccd::harness {

/// One method on one file (or on all files: file = "(all)"), fields as docs/DESIGN.md §5.
struct QueryScore {
  std::string method;
  std::string file;
  double thickness = 0.0;
  std::size_t queries = 0;
  std::size_t positives = 0;
  std::size_t reported = 0;
  std::size_t false_negatives = 0;
  std::size_t false_positives = 0;
  /// Queries without a truth label: counted in `reported` but in neither error count. positives, FN and FP count
  /// the labelled queries only; with none labelled they are unknown, shown as '-' and written as null.
  std::size_t unlabelled = 0;
  bool any_labelled() const { return unlabelled < queries; }
  /// A count over the labelled queries (positives, FN, FP), none when no query is labelled.
  std::optional<std::size_t> labelled(std::size_t count) const { return any_labelled() ? std::optional<std::size_t>(count) : std::nullopt; }
  /// Median over repeats of (time for the file / queries).
  double ns_per_query = 0.0;
  /// With TOIs (QueryScoringRequest::toi), over the queries that collide and that the method reports with a time:
  /// how many, how many later than the exact earliest contact (decided exactly), the largest and summed error.
  bool with_toi = false;
  std::size_t toi_checked = 0;
  std::size_t toi_late = 0;
  double toi_error_max = 0.0;
  double toi_error_sum = 0.0;
  /// Every checked query's error, for the median and the 99th percentile (nearest rank, harness/statistics.hpp).
  std::vector<double> toi_errors;
  /// First lines of the missed queries (for the regression library), at most 20.
  std::vector<std::size_t> false_negative_lines;
  /// Queries the method gave no answer to (QueryAnswer::fault), and the first kKeptQueryFaults of them.
  std::size_t errors = 0;
  struct ErrorQuery {
    std::size_t index = 0;
    std::size_t line = 0;
    std::string message;
  };
  std::vector<ErrorQuery> error_queries;
  /// Queries whose answer (outcome, TOI bits, or whether it was an error) differed between timed passes
  /// (--repeat N > 1): a method whose answers depend on what it was asked before.
  std::size_t changed_between_passes = 0;
  /// With QueryScoringRequest::keep_answers: every query's answer (first pass) and the exact TOI floor at δ (NaN
  /// where there is none, or where TOIs were not asked for).
  std::vector<QueryAnswer> answers;
  std::vector<double> exact_toi;
  std::vector<std::optional<bool>> labels;
};

/// Queries without an answer a score keeps whole (its count of errors covers every one).
inline constexpr std::size_t kKeptQueryFaults = 20;

/// The TOI error over a score's checked queries: max, mean, and the median and 99th percentile by nearest rank
/// (harness/statistics.hpp); none without TOIs or with none checked (never a 0 nobody measured).
struct ToiErrors {
  double max = 0, mean = 0, median = 0, p99 = 0;
};
std::optional<ToiErrors> toi_errors_of(const QueryScore& score);

/// A score as `queries --json` and the report's scores.json write it, a reporter over the type: counts over the
/// labelled queries null when none is labelled, the TOI error's statistics null when none was checked.
nlohmann::json score_row(const QueryScore& score);

struct QueryScoringRequest {
  std::vector<std::string> methods;
  double thickness = 0.0;
  int repeats = 1;
  /// Compare each reported TOI with the exact earliest contact (computed by the reference for every colliding
  /// query, outside the timed passes).
  bool toi = false;
  /// Keep every answer in the scores (`--write-answers`).
  bool keep_answers = false;
};

/// Writes every per-file score's answers (`--write-answers FILE`, answer_files.hpp): per query and method, the
/// method's answer and TOI, the file's label and the exact TOI floor. Atomic.
void write_query_answers(const std::filesystem::path& path, const std::vector<QueryScore>& scores);

/// The queries each method gave no answer to, written as query files under FAULTS/METHOD-HASH/KIND/FILE-HASH.csv (the
/// file's labels and the thickness they are for kept, scaled by 2^scale_exponent; HASH from the method's whole name and
/// from the file's whole path, so that two methods or two inputs never share a file), with FAULTS.txt beside them
/// saying which query, why, and the command that replays them; said on `out`.
void write_query_faults(const std::vector<QueryScore>& scores, const std::vector<datasets::QueryFile>& files, const std::filesystem::path& faults,
                        int scale_exponent, std::ostream& out);

/// The files with every query multiplied by 2^exponent (δ is scaled by the caller). Exact on the rationals, so a
/// labelled query keeps its label; a query whose doubles no longer equal its rationals (subnormal) takes the
/// doubles as the question and is labelled again by the reference at δ = 0 (what labels mean); one that overflows
/// is left out. @return the number of queries left out.
std::size_t scale_query_files(std::vector<datasets::QueryFile>& files, int exponent);

/// Scores every method of `request` (made as `methods`) on one file, one score per method in the request's order.
/// `moved(fraction)` is told how much of the file is done. A method from outside ccdbench (a plugin) that misses a
/// query of a file scored in one pass answers the file once more, untimed, and its answers that changed are counted
/// (changed_between_passes), as `run` audits a cell with misses.
std::vector<QueryScore> score_query_file(const datasets::QueryFile& file, const QueryScoringRequest& request, const QueryMethods& methods,
                                         const std::function<void(double)>& moved = {});
/// The same with its methods made for this file alone.
std::vector<QueryScore> score_query_file(const datasets::QueryFile& file, const QueryScoringRequest& request);

/// Appends one "(all)" score per method (in the order of `methods`, specs as given) summed over `scores`; ns per
/// query is weighted by each file's queries.
void append_query_totals(std::vector<QueryScore>& scores, const std::vector<std::string>& methods);

/// A score whole (sums, not means, every query's answer): its one serializer and reader, what MPI ranks exchange
/// (queries/records.cpp). What `queries --json` and the report write is a reporter over it (score_row).
void to_json(nlohmann::json& j, const QueryScore& score);
void to_json(nlohmann::json& j, const QueryScore::ErrorQuery& error);
void from_json(const nlohmann::json& j, QueryScore::ErrorQuery& error);
void from_json(const nlohmann::json& j, QueryScore& score);

/// Scores every method on every file (each method made once); returns per-file scores followed by one "(all)" score
/// per method. `moved(done, count)` is told how many files are done, a fraction of the one under way included.
std::vector<QueryScore> score_query_files(const std::vector<datasets::QueryFile>& files, const QueryScoringRequest& request,
                                          const std::function<void(double, std::size_t)>& moved = {});

/// The methods of a sweep: each narrow-phase variant of `methods` at a range of each of its accuracy parameters in
/// turn, its other keys as given (conservative: tolerance, then toi_tolerance; cubic32, cubic64, advancement: eta);
/// `exact` is kept as it is.
std::vector<std::string> sweep_methods(const std::vector<std::string>& methods);

/// Writes DIR/README.md (the table, with `command` written above it so the numbers can be reproduced) and
/// DIR/scores.json (the same rows), atomically.
void write_query_report(const std::filesystem::path& directory, const std::vector<QueryScore>& scores, const std::string& command);

/// A fixed-width table of the scores.
void print_query_scores(const std::vector<QueryScore>& scores, std::ostream& out);

}  // namespace ccd::harness
