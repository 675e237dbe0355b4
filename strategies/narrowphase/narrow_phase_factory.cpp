#include "strategies/narrowphase/advancement.hpp"
#include "strategies/narrowphase/cubic.hpp"
#include "strategies/narrowphase/inclusion.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"

#include <cmath>
#include <functional>
#include <stdexcept>

namespace ccd::narrowphase {
namespace {

/// Reads a variant's parameters; unknown keys and malformed or out-of-range values are errors.
class ParameterReader {
 public:
  ParameterReader(std::string variant, NarrowPhaseParameters parameters)
      : variant_(std::move(variant)), parameters_(std::move(parameters)) {}

  double number(const std::string& key, double fallback, double minimum) {
    const auto it = parameters_.find(key);
    if (it == parameters_.end()) return fallback;
    const double value = parse_spec_number(variant_, key, it->second, minimum);
    parameters_.erase(it);
    return value;
  }
  void finish(const std::string& known) {
    if (!parameters_.empty()) {
      throw std::invalid_argument(variant_ + " has no parameter '" + parameters_.begin()->first + "' (it has: " + known + ")");
    }
  }

 private:
  std::string variant_;
  NarrowPhaseParameters parameters_;
};

}  // namespace

double parse_spec_number(const std::string& owner, const std::string& key, const std::string& value, double minimum) {
  std::size_t used = 0;
  double number = 0;
  try {
    number = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value.size() || !std::isfinite(number) || number < minimum) {
    throw std::invalid_argument(owner + ": " + key + "=" + value + " must be a number >= " + std::to_string(minimum));
  }
  return number;
}

std::vector<std::string> narrow_phase_names() { return {"cubic32", "cubic64", "conservative", "advancement"}; }

std::unique_ptr<NarrowPhase> make_narrow_phase(const std::string& name, const NarrowPhaseParameters& parameters) {
  ParameterReader reader(name, parameters);
  if (name == "cubic32" || name == "cubic64") {
    CubicSettings settings;
    settings.eta = reader.number("eta", settings.eta, 0.0);
    reader.finish("eta");
    return make_cubic(name == "cubic32", settings);
  }
  if (name == "conservative") {
    InclusionSettings settings;
    settings.tolerance = reader.number("tolerance", settings.tolerance, 0.0);
    settings.max_iterations = static_cast<long>(reader.number("max_iterations", static_cast<double>(settings.max_iterations), 1.0));
    reader.finish("tolerance, max_iterations");
    return make_inclusion(settings);
  }
  if (name == "advancement") {
    AdvancementSettings settings;
    settings.eta = reader.number("eta", settings.eta, 0.0);
    settings.max_iterations = static_cast<long>(reader.number("max_iterations", static_cast<double>(settings.max_iterations), 1.0));
    reader.finish("eta, max_iterations");
    return make_advancement(settings);
  }
  std::string known;
  for (const std::string& n : narrow_phase_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown narrow phase '" + name + "' (known: " + known + ")");
}

std::pair<std::string, NarrowPhaseParameters> split_spec(const std::string& spec) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  while (true) {
    const std::size_t colon = spec.find(':', begin);
    parts.push_back(spec.substr(begin, colon == std::string::npos ? std::string::npos : colon - begin));
    if (colon == std::string::npos) break;
    begin = colon + 1;
  }
  NarrowPhaseParameters parameters;
  for (std::size_t i = 1; i < parts.size(); ++i) {
    const std::size_t equals = parts[i].find('=');
    if (equals == std::string::npos || equals == 0) throw std::invalid_argument("'" + parts[i] + "' in '" + spec + "' is not key=value");
    parameters[parts[i].substr(0, equals)] = parts[i].substr(equals + 1);
  }
  return {parts[0], parameters};
}

std::unique_ptr<NarrowPhase> make_narrow_phase_from_spec(const std::string& spec) {
  const auto [name, parameters] = split_spec(spec);
  return make_narrow_phase(name, parameters);
}

}  // namespace ccd::narrowphase
