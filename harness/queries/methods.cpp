#include "harness/queries/methods.hpp"

#include "strategies/narrowphase/entry_list.hpp"
#include "strategies/plugin/call_guard.hpp"

#include <stdexcept>

namespace ccd::harness {

// One declaration per file of the build's list (query_method_files.inc, generated from harness/CMakeLists.txt).
#define CCD_QUERY_METHOD_FILE(file) std::vector<QueryMethodEntry> file##_entries();
#include "ccd/query_method_files.inc"
#undef CCD_QUERY_METHOD_FILE

const std::vector<QueryMethodEntry>& query_method_entries() {
  static const std::vector<QueryMethodEntry> entries = narrowphase::gather_entries<QueryMethodEntry>({
#define CCD_QUERY_METHOD_FILE(file) file##_entries,
#include "ccd/query_method_files.inc"
#undef CCD_QUERY_METHOD_FILE
  });
  return entries;
}

reference::Decision decide_query_exactly(const datasets::Query& query, datasets::QueryKind kind, double thickness, bool toi) {
  reference::ExactPair pair;
  pair.kind = reference_kind(kind);
  pair.rows = query.exact;
  return reference::decide(pair, mpq_class(thickness), {true, toi, 64});
}

std::vector<QueryAnswer> QueryMethod::answer_all(const datasets::QueryFile& file, double thickness,
                                                 const std::function<void(std::size_t)>& answered) const {
  std::vector<QueryAnswer> answers(file.queries.size());
  for (std::size_t q = 0; q < file.queries.size(); ++q) {
    plugin::set_activity_item(q + 1);  // which query a plugin that ends the process was answering
    answers[q] = answer(file, q, thickness);
    if (answered && (q + 1) % kProgressQueries == 0) answered(q + 1);
  }
  return answers;
}

QueryMethods make_query_methods(const std::vector<std::string>& specs) {
  QueryMethods methods;
  for (const std::string& spec : specs) methods.push_back(make_query_method(spec));
  return methods;
}

void bind_answer_files(const std::vector<std::string>& methods, const std::vector<datasets::QueryFile>& files) {
  for (const QueryMethodEntry& entry : query_method_entries()) {
    if (entry.bind) entry.bind(methods, files);
  }
}

reference::PairKind reference_kind(datasets::QueryKind kind) {
  return kind == datasets::QueryKind::vertex_face ? reference::PairKind::vertex_face : reference::PairKind::edge_edge;
}

std::unique_ptr<QueryMethod> make_query_method(const std::string& spec) {
  for (const QueryMethodEntry& entry : query_method_entries()) {
    if (entry.takes(spec)) return entry.make(spec);
  }
  std::string known;
  for (const std::string& n : query_method_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown method '" + spec + "' (known: " + known + ")");
}

std::vector<std::string> query_method_names() {
  std::vector<std::string> names;
  for (const QueryMethodEntry& entry : query_method_entries()) {
    for (std::string& name : entry.names()) names.push_back(std::move(name));
  }
  return names;
}

}  // namespace ccd::harness
