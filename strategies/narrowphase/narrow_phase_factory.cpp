#include "strategies/narrowphase/advancement.hpp"
#include "strategies/narrowphase/cubic.hpp"
#include "strategies/narrowphase/inclusion.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <sstream>
#include <stdexcept>

namespace ccd::narrowphase {
namespace {

/// Reads a variant's parameters; unknown keys and malformed or out-of-range values are errors.
class ParameterReader {
 public:
  ParameterReader(std::string variant, NarrowPhaseParameters parameters)
      : variant_(std::move(variant)), parameters_(std::move(parameters)) {}

  double number(const std::string& key, double fallback, SpecRange range) {
    const auto it = parameters_.find(key);
    if (it == parameters_.end()) return fallback;
    const double value = parse_spec_number(variant_, key, it->second, range);
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

// Ranges of the narrow phases' keys. Tolerances and eta are fractions of the pair's bounding-box diagonal: 1 is
// already the whole pair. An iteration is one sub-box (or one advancement step) of about 100 ns: 1e9 caps a single
// query at minutes, far beyond any use, and keeps the count exact in a long.
constexpr SpecRange kFractionRange{0.0, 1.0};
constexpr SpecRange kIterationRange{1.0, 1e9, true};

std::string format_spec_number(double value) {
  // As an ostream prints it (6 significant digits) when that reads back as the same double, so that the names of
  // existing results stay; otherwise the shortest text that does.
  std::ostringstream six;
  six << value;
  if (std::strtod(six.str().c_str(), nullptr) == value) return six.str();
  char text[32];
  const auto [end, error] = std::to_chars(text, text + sizeof(text), value);
  if (error != std::errc()) return six.str();
  return std::string(text, end);
}

double parse_spec_number(const std::string& owner, const std::string& key, const std::string& value, SpecRange range) {
  std::size_t used = 0;
  double number = 0;
  try {
    number = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value.size() || !std::isfinite(number) || number < range.minimum || number > range.maximum ||
      (range.integer && number != std::floor(number))) {
    std::ostringstream message;
    message << owner << ": " << key << "=" << value << " must be " << (range.integer ? "an integer" : "a number")
            << " in [" << range.minimum << ", " << range.maximum << "]";
    throw std::invalid_argument(message.str());
  }
  return number;
}

std::vector<std::string> narrow_phase_parameter_names(const std::string& name) {
  if (name == "cubic32" || name == "cubic64") return {"eta"};
  if (name == "conservative") return {"tolerance", "max_iterations"};
  if (name == "advancement") return {"eta", "max_iterations"};
  return {};
}

std::vector<std::string> narrow_phase_names() { return {"cubic32", "cubic64", "conservative", "advancement"}; }

CubicSettings read_cubic_settings(const std::string& name, const NarrowPhaseParameters& parameters) {
  ParameterReader reader(name, parameters);
  CubicSettings settings;
  settings.eta = reader.number("eta", settings.eta, kFractionRange);
  reader.finish("eta");
  return settings;
}

InclusionSettings read_inclusion_settings(const NarrowPhaseParameters& parameters) {
  ParameterReader reader("conservative", parameters);
  InclusionSettings settings;
  settings.tolerance = reader.number("tolerance", settings.tolerance, kFractionRange);
  settings.max_iterations = static_cast<long>(reader.number("max_iterations", static_cast<double>(settings.max_iterations), kIterationRange));
  reader.finish("tolerance, max_iterations");
  return settings;
}

std::unique_ptr<NarrowPhase> make_narrow_phase(const std::string& name, const NarrowPhaseParameters& parameters) {
  if (name == "cubic32" || name == "cubic64") return make_cubic(name == "cubic32", read_cubic_settings(name, parameters));
  if (name == "conservative") return make_inclusion(read_inclusion_settings(parameters));
  ParameterReader reader(name, parameters);
  if (name == "advancement") {
    AdvancementSettings settings;
    settings.eta = reader.number("eta", settings.eta, kFractionRange);
    settings.max_iterations = static_cast<long>(reader.number("max_iterations", static_cast<double>(settings.max_iterations), kIterationRange));
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
