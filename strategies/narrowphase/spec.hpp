#pragma once
/// @file
/// The words of a spec, `NAME[+NARROW][:key=value...]` (docs/DESIGN.md §3): how a key is declared (name, values, default,
/// help), how its value is read and checked, and how a resolved name prints a number. The registries of strategies
/// and narrow phases declare their keys with these, so that parsing, error messages, `ccdbench strategies` and the
/// resolved names all come from one declaration per key.

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace ccd::narrowphase {

/// Parameters as given in a spec (`key=value`), before their owner checks them.
using SpecParameters = std::map<std::string, std::string>;

/// The values a numeric spec key accepts: [minimum, maximum], whole numbers only when `integer`. Every numeric key
/// has one, so that no value converts into something else (1e300 iterations into a negative count).
struct SpecRange {
  double minimum;
  double maximum;
  bool integer = false;
};

/// A narrow phase's tolerance, a fraction of the pair's bounding-box diagonal: 1 is already the whole pair.
inline constexpr SpecRange kFractionOfPairRange{0.0, 1.0};
/// A span of time, a fraction of the step: 1 is already the whole step.
inline constexpr SpecRange kFractionOfStepRange{0.0, 1.0};
/// An iteration cap. An iteration (a sub-box, an advancement step) costs about 100 ns: 1e9 caps a single query at
/// minutes, far beyond any use, and keeps the count exact in a long.
inline constexpr SpecRange kIterationRange{1.0, 1e9, true};

/// One key a spec may carry, as `ccdbench strategies` lists it and as SpecReader checks it.
struct KeySpec {
  enum class Kind { number, integer, choice, text };
  std::string name;
  Kind kind = Kind::number;
  /// number, integer: the accepted values.
  SpecRange range{0, 0};
  /// choice: the accepted values, each as the resolved name prints it.
  std::vector<std::string> choices;
  /// choice: other spellings and the choice each means ("true" -> "on").
  std::vector<std::pair<std::string, std::string>> aliases;
  /// The value taken when the key is not given, as the resolved name prints it ("" for a text key: none).
  std::string default_value;
  /// One line: what the key changes.
  std::string help;

  static KeySpec number(std::string name, double default_value, SpecRange range, std::string help);
  static KeySpec integer(std::string name, long default_value, SpecRange range, std::string help);
  static KeySpec choice(std::string name, std::vector<std::string> choices, std::string default_value, std::string help,
                        std::vector<std::pair<std::string, std::string>> aliases = {});
  /// on or off (also true/false, 1/0).
  static KeySpec on_off(std::string name, bool default_value, std::string help);
  static KeySpec text(std::string name, std::string help);

  /// What the key accepts, for listings: "[0, 1]", "integer in [1, 1e+09]", "on|off", "text".
  std::string allowed() const;
};

/// Reads one owner's keys from a spec's parameters against their declarations.
class SpecReader {
 public:
  /// `owner` names the keys' owner in messages ("conservative", "apccd").
  SpecReader(std::string owner, const std::vector<KeySpec>& keys, SpecParameters parameters);

  /// The key's value, or its default when not given.
  /// @throws std::invalid_argument "OWNER: KEY=VALUE must be ..." for a value it does not accept.
  double number(const std::string& key) const;
  long integer(const std::string& key) const;
  /// The chosen value as the resolved name prints it (an alias is read as its choice).
  std::string choice(const std::string& key) const;
  std::string text(const std::string& key) const;
  bool given(const std::string& key) const { return parameters_.count(key) > 0; }

 private:
  const KeySpec& declared(const std::string& key, KeySpec::Kind kind) const;
  std::string owner_;
  const std::vector<KeySpec>& keys_;
  SpecParameters parameters_;
};

/// The value of spec key `key` of `owner` (the whole text must be a number within `range`).
/// @throws std::invalid_argument "OWNER: KEY=VALUE must be a number in [MIN, MAX]" (or "an integer") otherwise.
double parse_spec_number(const std::string& owner, const std::string& key, const std::string& value, SpecRange range);

/// `value` as a resolved name prints it: the shortest text that reads back as the same double (std::to_chars),
/// so specs that differ in any bit get different names and cell keys (1e-06 and 1.0000001e-06).
std::string format_spec_number(double value);

/// The names of `keys`, comma-separated ("none" for none), for messages.
std::string key_names(const std::vector<KeySpec>& keys);

/// The heads that name code or answers from outside ccdbench: plugin:PATH (a shared library,
/// strategies/plugin/ccdbench_plugin.h), answers:DIR (a folder of answer files) and callable:NAME (a method of the
/// calling program, strategies/plugin/host_method.hpp). The path or name is one part of the spec: it may not hold ':'.
inline constexpr const char* kPluginHead = "plugin";
inline constexpr const char* kAnswersHead = "answers";
inline constexpr const char* kHostMethodHead = "callable";
bool is_file_head(const std::string& head);

/// Splits `HEAD[:key=value...]` into HEAD and its parameters; a head that names a file (`plugin:PATH`, and
/// `NAME+plugin:PATH`) keeps its path: ("plugin:PATH", keys). @throws std::invalid_argument for a malformed key or a
/// file head without a path.
std::pair<std::string, SpecParameters> split_spec(const std::string& spec);

}  // namespace ccd::narrowphase
