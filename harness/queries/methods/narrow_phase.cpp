// Query methods: every narrow phase of the registry (a plugin, `plugin:PATH`, is one) on the doubles the query's
// rationals round to.

#include "harness/queries/methods.hpp"
#include "strategies/narrowphase_registry.hpp"

#include <algorithm>
#include <span>

namespace ccd::harness {
namespace {

/// A narrow phase's result as a query's answer.
QueryAnswer query_answer(narrowphase::NarrowPhaseResult result) {
  return {result.collides, result.collides ? result.toi : std::numeric_limits<double>::quiet_NaN(), std::move(result.fault)};
}

/// A narrow-phase variant on the doubles the query's rationals round to (what a simulator would hand it).
class NarrowPhaseQueryMethod final : public QueryMethod {
 public:
  explicit NarrowPhaseQueryMethod(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase) : narrow_phase_(std::move(narrow_phase)) {}
  std::string name() const override { return narrow_phase_->name(); }
  QueryAnswer answer(const datasets::QueryFile& file, std::size_t index, double thickness) const override {
    const datasets::Query& query = file.queries[index];
    return query_answer(file.kind == datasets::QueryKind::vertex_face ? narrow_phase_->vertex_face(query.rounded, thickness)
                                                                      : narrow_phase_->edge_edge(query.rounded, thickness));
  }
  std::vector<QueryAnswer> answer_all(const datasets::QueryFile& file, double thickness,
                                      const std::function<void(std::size_t)>& answered) const override {
    if (!narrow_phase_->prefers_batches()) return QueryMethod::answer_all(file, thickness, answered);
    std::vector<narrowphase::NarrowPhase::BatchPair> pairs;
    pairs.reserve(file.queries.size());
    for (const datasets::Query& query : file.queries) pairs.push_back({&query.rounded, file.kind == datasets::QueryKind::vertex_face, thickness});
    std::vector<narrowphase::NarrowPhaseResult> results(pairs.size());
    // A batch at a time, so that progress moves on a long file (one batch of an isolated plugin each).
    for (std::size_t first = 0; first < pairs.size(); first += kProgressQueries) {
      const std::size_t count = std::min(kProgressQueries, pairs.size() - first);
      narrow_phase_->answer_batch(std::span(pairs).subspan(first, count), std::span(results).subspan(first, count));
      if (answered) answered(first + count);
    }
    std::vector<QueryAnswer> answers;
    answers.reserve(results.size());
    for (narrowphase::NarrowPhaseResult& result : results) answers.push_back(query_answer(std::move(result)));
    return answers;
  }

 private:
  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase_;
};

}  // namespace

std::vector<QueryMethodEntry> narrow_phase_entries() {
  return {{[](const std::string& spec) { return narrowphase::is_narrow_phase(narrowphase::split_spec(spec).first); },
           [](const std::string& spec) -> std::unique_ptr<QueryMethod> {
             return std::make_unique<NarrowPhaseQueryMethod>(narrowphase::make_narrow_phase_from_spec(spec));
           },
           [] {
             std::vector<std::string> names;
             for (const narrowphase::NarrowPhaseEntry& entry : narrowphase::narrow_phases()) names.push_back(entry.name);
             return names;
           }}};
}

}  // namespace ccd::harness
