#pragma once
/// @file
/// The methods `ccdbench queries` scores (`--method`): a way of answering one query, and the registry that makes one
/// from its spec.

#include "datasets/query_file.hpp"
#include "reference/elementary_pair.hpp"

#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace ccd::harness {

/// The reference's name for a query file's kind.
reference::PairKind reference_kind(datasets::QueryKind kind);

/// A method's answer to one query: whether it collides and, when the method reports one, the time of impact.
struct QueryAnswer {
  bool collides = false;
  /// NaN when the method reports no time.
  double toi = std::numeric_limits<double>::quiet_NaN();
  /// Not empty when the method gave no answer (a plugin's error or undecided answer, an answer ccdbench refused, a
  /// crash or a hang under isolation, `error` in an answer file): why. `collides` then says how it counts.
  std::string fault;
};

/// A way of answering "do these primitives come within δ during the step?" for one query.
class QueryMethod {
 public:
  virtual ~QueryMethod() = default;
  virtual std::string name() const = 0;
  /// The answer for query `index` of `file` at thickness δ (the method decides whether it uses the exact rationals
  /// or the doubles they round to).
  virtual QueryAnswer answer(const datasets::QueryFile& file, std::size_t index, double thickness) const = 0;
  /// Every query of `file`, in order: one `answer` each, or, for a method that prefers batches (an isolated
  /// plugin), the whole file in batches. What is timed as the method's work on the file. `answered(n)` is told how
  /// many are answered every kProgressQueries or so (progress on a long file).
  virtual std::vector<QueryAnswer> answer_all(const datasets::QueryFile& file, double thickness,
                                              const std::function<void(std::size_t)>& answered = {}) const;
};

/// How many queries a method answers between two calls of answer_all's `answered` (a batch of an isolated plugin).
inline constexpr std::size_t kProgressQueries = 4096;

/// The methods of a scoring, made once for every file a process scores: an isolated plugin's child starts once,
/// before any timed pass, instead of once per file inside the first.
using QueryMethods = std::vector<std::unique_ptr<QueryMethod>>;
QueryMethods make_query_methods(const std::vector<std::string>& specs);

/// The method that is the reference itself (certified filter, then exact root isolation, on the rationals).
inline constexpr const char* kExactMethod = "exact";

/// Methods by spec, through the registry below: `exact`, a narrow phase of the registry `NAME[:key=value...]` on the rounded doubles (a plugin,
/// `plugin:PATH[:key=value]`, is one), a strategy with elementary tests of its own (fcl), by its name, or an answer
/// file, `answers:FILE[:method=NAME]` (answer_files.hpp; bind_answer_files first).
/// @throws std::invalid_argument naming the known methods for an unknown name or parameter.
std::unique_ptr<QueryMethod> make_query_method(const std::string& spec);

/// Reads every answer file among `methods` and matches its lines to the queries of `files`.
/// @throws InputError (FILE:line N: REASON) for a malformed file, or one that does not answer exactly these queries.
void bind_answer_files(const std::vector<std::string>& methods, const std::vector<datasets::QueryFile>& files);
std::vector<std::string> query_method_names();

/// One kind of query method, an entry of the query-method registry as strategies and narrow phases have theirs
/// (docs/DESIGN.md §9): harness/queries/methods/FILE.cpp defines `std::vector<QueryMethodEntry> FILE_entries()`, and
/// harness/CMakeLists.txt lists the file. A spec is made by the first entry, in the list's order, that takes it.
struct QueryMethodEntry {
  /// Whether `spec` names a method of this entry.
  std::function<bool(const std::string& spec)> takes;
  std::function<std::unique_ptr<QueryMethod>(const std::string& spec)> make;
  /// The names it offers, in the list of known methods (none for an entry whose methods are paths).
  std::function<std::vector<std::string>()> names;
  /// Told every method spec of a scoring and its files before any method is made (answer files match lines here);
  /// may be empty. @throws InputError for a file that does not answer these queries.
  std::function<void(const std::vector<std::string>&, const std::vector<datasets::QueryFile>&)> bind = {};
};

/// Every entry, in the build's order.
const std::vector<QueryMethodEntry>& query_method_entries();

/// The reference on the query's exact rationals at δ = thickness (with its exact TOI floor when `toi`).
reference::Decision decide_query_exactly(const datasets::Query& query, datasets::QueryKind kind, double thickness, bool toi);

}  // namespace ccd::harness
