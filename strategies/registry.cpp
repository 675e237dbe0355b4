#include "strategies/registry.hpp"

#include "strategies/narrowphase/entry_list.hpp"
#include "strategies/narrowphase/registry.hpp"

#include <algorithm>
#include <stdexcept>

namespace ccd::strategies {

// One declaration per file of the build's list (strategy_files.inc, generated from CMakeLists.txt).
#define CCD_STRATEGY_FILE(file) std::vector<StrategyEntry> file##_entries();
#include "ccd/strategy_files.inc"
#undef CCD_STRATEGY_FILE

const std::vector<StrategyEntry>& strategy_entries() {
  static const std::vector<StrategyEntry> entries = narrowphase::gather_entries<StrategyEntry>({
#define CCD_STRATEGY_FILE(file) file##_entries,
#include "ccd/strategy_files.inc"
#undef CCD_STRATEGY_FILE
  });
  return entries;
}

const StrategyEntry& find_strategy(const std::string& name) { return narrowphase::entry_named(strategy_entries(), name, "strategy"); }

StrategySpec parse_strategy_spec(const std::string& spec) {
  StrategySpec parsed;
  auto [head, parameters] = narrowphase::split_spec(spec);
  const std::size_t plus = head.find('+');
  parsed.name = head.substr(0, plus);
  if (plus != std::string::npos) {
    parsed.narrow_phase = head.substr(plus + 1);
    if (parsed.narrow_phase.empty()) throw std::invalid_argument("malformed strategy spec '" + spec + "'");
  }
  if (parsed.name.empty()) throw std::invalid_argument("malformed strategy spec '" + spec + "'");
  parsed.parameters = std::move(parameters);
  return parsed;
}

StrategySpec strategy_names_of(const std::string& spec) {
  const std::string head = spec.substr(0, spec.find(':'));
  const std::size_t plus = head.find('+');
  return {head.substr(0, plus), plus == std::string::npos ? std::string() : head.substr(plus + 1), {}};
}

const StrategyEntry& strategy_entry_of(const std::string& spec) { return find_strategy(strategy_names_of(spec).name); }

std::unique_ptr<Strategy> make_strategy(const std::string& spec) {
  const StrategySpec parsed = parse_strategy_spec(spec);
  const StrategyEntry& entry = find_strategy(parsed.name);
  if (!entry.unavailable.empty()) throw std::invalid_argument(entry.name + " is not available: " + entry.unavailable);
  auto owns = [](const std::vector<narrowphase::KeySpec>& keys, const std::string& key) {
    return std::any_of(keys.begin(), keys.end(), [&](const narrowphase::KeySpec& k) { return k.name == key; });
  };
  if (!entry.takes_narrow_phase) {
    if (!parsed.narrow_phase.empty()) {
      throw std::invalid_argument(entry.name + " uses elementary tests of its own and takes no narrow phase ('" + spec + "')");
    }
    return entry.make({narrowphase::SpecReader(entry.name, entry.keys, parsed.parameters), nullptr});
  }
  const narrowphase::NarrowPhaseEntry& narrow =
      narrowphase::find_narrow_phase(parsed.narrow_phase.empty() ? narrowphase::kDefaultNarrowPhase : parsed.narrow_phase);
  // Each key to its owner; one that neither has is refused naming both lists (so `apccd:foo=1` is not blamed on
  // the narrow phase alone).
  narrowphase::SpecParameters own, narrow_keys;
  for (const auto& [key, value] : parsed.parameters) {
    if (owns(entry.keys, key)) {
      own[key] = value;
    } else if (owns(narrow.keys, key)) {
      narrow_keys[key] = value;
    } else {
      throw std::invalid_argument(entry.name + "+" + narrow.name + " has no parameter '" + key + "' (" + entry.name + "'s: " +
                                  narrowphase::key_names(entry.keys) + "; narrow phase " + narrow.name + "'s: " +
                                  narrowphase::key_names(narrow.keys) + ")");
    }
  }
  const narrowphase::SpecReader keys(entry.name, entry.keys, own);
  return entry.make({keys, narrow.make(narrowphase::SpecReader(narrow.name, narrow.keys, narrow_keys))});
}

}  // namespace ccd::strategies
