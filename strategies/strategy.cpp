#include "strategies/strategy.hpp"

#include "strategies/narrowphase/narrow_phase.hpp"

#include "strategies/apccd/cpu/apccd.hpp"
#include "strategies/apccd/opencl/apccd_opencl.hpp"
#include "strategies/full_traversal/full_traversal.hpp"
#include "strategies/opencl/full_opencl.hpp"

#include "ccd/config.hpp"
#if CCDBENCH_WITH_FCL
#include "strategies/fcl/fcl_strategies.hpp"
#endif

#include <algorithm>
#include <stdexcept>

namespace ccd::strategies {

StrategySpec parse_strategy_spec(const std::string& spec) {
  StrategySpec parsed;
  const auto [head, parameters] = narrowphase::split_spec(spec);
  const std::size_t plus = head.find('+');
  parsed.name = head.substr(0, plus);
  if (plus != std::string::npos) parsed.narrow_phase = head.substr(plus + 1);
  if (parsed.name.empty() || parsed.narrow_phase.empty()) throw std::invalid_argument("malformed strategy spec '" + spec + "'");
  parsed.parameters = parameters;
  return parsed;
}

std::vector<std::string> strategy_names() {
  std::vector<std::string> names{"full", "apccd", "brute"};
  if (CCDBENCH_WITH_FCL) names.insert(names.end(), {"fcl", "fcl-bvh"});
  return names;
}

namespace {

std::string joined(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text.empty() ? "none" : text;
}

/// Refuses a key that neither the strategy nor its narrow phase has, naming both lists (so `apccd:foo=1` is not
/// blamed on the narrow phase alone).
void reject_unknown_keys(const StrategySpec& parsed, const std::vector<std::string>& own) {
  const std::vector<std::string> narrow = narrowphase::narrow_phase_parameter_names(parsed.narrow_phase);
  for (const auto& [key, value] : parsed.parameters) {
    if (std::find(own.begin(), own.end(), key) != own.end() || std::find(narrow.begin(), narrow.end(), key) != narrow.end()) continue;
    throw std::invalid_argument(parsed.name + "+" + parsed.narrow_phase + " has no parameter '" + key + "' (" + parsed.name +
                                "'s: " + joined(own) + "; narrow phase " + parsed.narrow_phase + "'s: " + joined(narrow) + ")");
  }
}

}  // namespace

std::unique_ptr<Strategy> make_strategy(const std::string& spec) {
  const StrategySpec parsed = parse_strategy_spec(spec);
  const auto narrow_names = narrowphase::narrow_phase_names();
  if (parsed.name != "fcl" && std::find(narrow_names.begin(), narrow_names.end(), parsed.narrow_phase) == narrow_names.end()) {
    throw std::invalid_argument("unknown narrow phase '" + parsed.narrow_phase + "' in '" + spec + "' (known: " + joined(narrow_names) + ")");
  }
  if (parsed.name == "full") {
    std::vector<std::string> own = backend_parameter_names();
    own.push_back("filter");
    reject_unknown_keys(parsed, own);
  }
  if (parsed.name == "brute") reject_unknown_keys(parsed, {});
  if (parsed.name == "apccd") {
    std::vector<std::string> own = apccd_parameter_names();
    const std::vector<std::string> backend = backend_parameter_names();
    own.insert(own.end(), backend.begin(), backend.end());
    reject_unknown_keys(parsed, own);
  }
  if (parsed.name == "fcl-bvh") reject_unknown_keys(parsed, {"bv"});
  // `full` has only the backend keys and filter of its own and `brute` none: every other key is the narrow phase's.
  if (parsed.name == "full" || parsed.name == "brute") {
    std::map<std::string, std::string> parameters = parsed.parameters;
    const BackendChoice backend = parsed.name == "full" ? take_backend(parameters) : BackendChoice{};
    const bool filter = parsed.name == "full" && take_full_filter(parameters);
    auto narrow_phase = narrowphase::make_narrow_phase(parsed.narrow_phase, parameters);
    if (backend.backend == "opencl") return make_full_opencl(std::move(narrow_phase), parsed.narrow_phase, parameters, backend, filter);
    return parsed.name == "full" ? make_full_traversal(std::move(narrow_phase), filter) : make_brute_force(std::move(narrow_phase));
  }
  if (parsed.name == "apccd") {
    std::map<std::string, std::string> parameters = parsed.parameters;
    const BackendChoice backend = take_backend(parameters);
    const ApccdSettings settings = take_apccd_settings(parameters);
    auto narrow_phase = narrowphase::make_narrow_phase(parsed.narrow_phase, parameters);
    if (backend.backend == "opencl") return make_apccd_opencl(settings, std::move(narrow_phase), parsed.narrow_phase, parameters, backend);
    return make_apccd(settings, std::move(narrow_phase));
  }
  if (parsed.name == "fcl" || parsed.name == "fcl-bvh") {
#if CCDBENCH_WITH_FCL
    if (parsed.name == "fcl") {
      if (spec.find('+') != std::string::npos) {
        throw std::invalid_argument("fcl uses FCL's own elementary tests and takes no narrow phase ('" + spec +
                                    "'); for FCL's broad phase with a narrow phase of this project use fcl-bvh+NARROW");
      }
      return make_fcl(parsed.parameters);
    }
    return make_fcl_bvh(parsed.parameters, parsed.narrow_phase);
#else
    throw std::invalid_argument(parsed.name + " is not available: this build has CCDBENCH_WITH_FCL=OFF (install libfcl-dev "
                                "libccd-dev, which scripts/setup.sh does, and reconfigure)");
#endif
  }
  std::string known;
  for (const std::string& name : strategy_names()) known += (known.empty() ? "" : ", ") + name;
  throw std::invalid_argument("unknown strategy '" + parsed.name + "' (known: " + known + ")");
}

}  // namespace ccd::strategies
