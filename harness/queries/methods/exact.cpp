// Query method `exact`: the reference itself on the query's rationals.

#include "harness/queries/methods.hpp"

namespace ccd::harness {
namespace {

/// The reference on the query's exact rationals: the harness calling the oracle, not a strategy's narrow phase.
class ExactQueryMethod final : public QueryMethod {
 public:
  std::string name() const override { return kExactMethod; }
  QueryAnswer answer(const datasets::QueryFile& file, std::size_t index, double thickness) const override {
    return {decide_query_exactly(file.queries[index], file.kind, thickness, false).collides, std::numeric_limits<double>::quiet_NaN(), {}};
  }
};
}  // namespace

std::vector<QueryMethodEntry> exact_entries() {
  return {{[](const std::string& spec) { return spec == kExactMethod; },
           [](const std::string&) -> std::unique_ptr<QueryMethod> { return std::make_unique<ExactQueryMethod>(); },
           [] { return std::vector<std::string>{kExactMethod}; }}};
}

}  // namespace ccd::harness
