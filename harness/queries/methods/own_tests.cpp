// Query methods: a strategy's elementary tests of its own (fcl's), by the strategy's name.

#include "harness/queries/methods.hpp"
#include "strategies/registry.hpp"

#include <stdexcept>

namespace ccd::harness {
namespace {

/// A strategy's elementary tests of its own (fcl's, StrategyEntry::elementary_test), at δ = 0 only.
class OwnTestsQueryMethod final : public QueryMethod {
 public:
  explicit OwnTestsQueryMethod(const strategies::StrategyEntry& strategy) : strategy_(strategy) {}
  std::string name() const override { return strategy_.name; }
  QueryAnswer answer(const datasets::QueryFile& file, std::size_t index, double thickness) const override {
    if (thickness > 0) throw std::invalid_argument("method " + strategy_.name + " has no thickness: run it with --thickness 0");
    // No time: such tests answer yes or no.
    return {strategy_.elementary_test(file.queries[index].rounded, file.kind == datasets::QueryKind::vertex_face),
            std::numeric_limits<double>::quiet_NaN(),
            {}};
  }

 private:
  const strategies::StrategyEntry& strategy_;
};
/// The strategy named `spec` with elementary tests of its own, or nullptr.
const strategies::StrategyEntry* own_tests(const std::string& spec) {
  for (const strategies::StrategyEntry& strategy : strategies::strategy_entries()) {
    if (strategy.name == spec && strategy.elementary_test) return &strategy;
  }
  return nullptr;
}

}  // namespace

std::vector<QueryMethodEntry> own_tests_entries() {
  return {{[](const std::string& spec) { return own_tests(spec) != nullptr; },
           [](const std::string& spec) -> std::unique_ptr<QueryMethod> { return std::make_unique<OwnTestsQueryMethod>(*own_tests(spec)); },
           [] {
             std::vector<std::string> names;
             for (const strategies::StrategyEntry& strategy : strategies::strategy_entries()) {
               if (strategy.elementary_test) names.push_back(strategy.name);
             }
             return names;
           }}};
}

}  // namespace ccd::harness
