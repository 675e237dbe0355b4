#pragma once
/// @file
/// The elementary tests every strategy shares (DESIGN.md §3): one vertex-face and one edge-edge call on a pair
/// with linear motion over the step, thickness δ >= 0. Variants differ in precision and in what they guarantee.

#include "core/vec.hpp"

#include <array>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace ccd::narrowphase {

/// Rows in the query files' order: VF v_t0, f0_t0, f1_t0, f2_t0, v_t1, f0_t1, f1_t1, f2_t1;
/// EE ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1.
using PairRows = std::array<Vec3, 8>;

/// What a test answers, with what a user needs to judge it (STYLE.md "Shape").
struct NarrowPhaseResult {
  bool collides = false;
  /// Earliest time of contact in [0, 1] when collides (conservative variants: never later than the true one);
  /// NaN otherwise.
  double toi = std::numeric_limits<double>::quiet_NaN();
  /// The iteration cap stopped the test; a conservative variant then answers "collides".
  bool hit_iteration_cap = false;
  /// The distance tolerance the answer was reached with (0 when exact up to rounding).
  double achieved_tolerance = 0.0;
};

class NarrowPhase {
 public:
  virtual ~NarrowPhase() = default;
  /// The resolved spec: name and every parameter with its value, e.g. "cubic64:eta=1e-06".
  virtual std::string name() const = 0;
  /// Whether the variant promises no false negatives on any input.
  virtual bool conservative() const = 0;
  virtual NarrowPhaseResult vertex_face(const PairRows& rows, double thickness) const = 0;
  virtual NarrowPhaseResult edge_edge(const PairRows& rows, double thickness) const = 0;
};

/// Parameters as given in a spec (`key=value`), before the variant checks them.
using NarrowPhaseParameters = std::map<std::string, std::string>;

/// `cubic32`, `cubic64`, `conservative`, `advancement`, with optional parameters.
/// @throws std::invalid_argument naming the variants (or the variant's parameters) for an unknown name or key,
///         and for a value out of range.
std::unique_ptr<NarrowPhase> make_narrow_phase(const std::string& name, const NarrowPhaseParameters& parameters = {});

/// The values a numeric spec key accepts: [minimum, maximum], whole numbers only when `integer`. Every key has
/// one, so that no value converts into something else (1e300 iterations into a negative count).
struct SpecRange {
  double minimum;
  double maximum;
  bool integer = false;
};

/// The value of spec key `key` of `owner` (the whole text must be a number within `range`).
/// @throws std::invalid_argument "OWNER: KEY=VALUE must be a number in [MIN, MAX]" (or "an integer") otherwise.
double parse_spec_number(const std::string& owner, const std::string& key, const std::string& value, SpecRange range);

/// `value` as a spec prints it: as an ostream does (6 significant digits: 0.25, 1e-06, 100000) when that reads back
/// as the same double, else the shortest text that does (1.0000000001), so specs that differ in any digit get
/// different names.
std::string format_spec_number(double value);

/// The keys a narrow phase accepts (empty for an unknown name).
std::vector<std::string> narrow_phase_parameter_names(const std::string& name);

/// Splits `HEAD[:key=value...]` into HEAD and its parameters. @throws std::invalid_argument for a malformed key.
std::pair<std::string, NarrowPhaseParameters> split_spec(const std::string& spec);

/// Parses `NAME[:key=value...]` and makes the variant.
std::unique_ptr<NarrowPhase> make_narrow_phase_from_spec(const std::string& spec);

std::vector<std::string> narrow_phase_names();

}  // namespace ccd::narrowphase
