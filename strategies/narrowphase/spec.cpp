#include "strategies/narrowphase/spec.hpp"

#include "core/number_text.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace ccd::narrowphase {
namespace {

/// "a", "a or b", "a, b or c".
std::string alternatives(const std::vector<std::string>& values) {
  std::string text;
  for (std::size_t i = 0; i < values.size(); ++i) {
    text += (i == 0 ? "" : i + 1 == values.size() ? " or " : ", ") + values[i];
  }
  return text;
}

/// The choice `value` means (itself or through an alias), or "" when it means none.
std::string choice_meant(const KeySpec& key, const std::string& value) {
  if (std::find(key.choices.begin(), key.choices.end(), value) != key.choices.end()) return value;
  for (const auto& [alias, meant] : key.aliases) {
    if (alias == value) return meant;
  }
  return {};
}

}  // namespace

KeySpec KeySpec::number(std::string name, double default_value, SpecRange range, std::string help) {
  return {std::move(name), Kind::number, range, {}, {}, format_spec_number(default_value), std::move(help)};
}

KeySpec KeySpec::integer(std::string name, long default_value, SpecRange range, std::string help) {
  range.integer = true;
  return {std::move(name), Kind::integer, range, {}, {}, std::to_string(default_value), std::move(help)};
}

KeySpec KeySpec::choice(std::string name, std::vector<std::string> choices, std::string default_value, std::string help,
                        std::vector<std::pair<std::string, std::string>> aliases) {
  return {std::move(name), Kind::choice, {0, 0}, std::move(choices), std::move(aliases), std::move(default_value), std::move(help)};
}

KeySpec KeySpec::on_off(std::string name, bool default_value, std::string help) {
  return choice(std::move(name), {"on", "off"}, default_value ? "on" : "off", std::move(help),
                {{"true", "on"}, {"1", "on"}, {"false", "off"}, {"0", "off"}});
}

KeySpec KeySpec::text(std::string name, std::string help) { return {std::move(name), Kind::text, {0, 0}, {}, {}, "", std::move(help)}; }

std::string KeySpec::allowed() const {
  std::ostringstream text;
  switch (kind) {
    case Kind::number: text << "[" << format_spec_number(range.minimum) << ", " << format_spec_number(range.maximum) << "]"; break;
    case Kind::integer: text << "integer in [" << format_spec_number(range.minimum) << ", " << format_spec_number(range.maximum) << "]"; break;
    case Kind::choice:
      for (std::size_t i = 0; i < choices.size(); ++i) text << (i ? "|" : "") << choices[i];
      break;
    case Kind::text: text << "text"; break;
  }
  return text.str();
}

SpecReader::SpecReader(std::string owner, const std::vector<KeySpec>& keys, SpecParameters parameters)
    : owner_(std::move(owner)), keys_(keys), parameters_(std::move(parameters)) {
  // Every given key is checked here, read or not, so that no bad value passes unnoticed.
  for (const auto& [name, value] : parameters_) {
    const auto key = std::find_if(keys_.begin(), keys_.end(), [&](const KeySpec& k) { return k.name == name; });
    if (key == keys_.end()) throw std::invalid_argument(owner_ + " has no parameter '" + name + "' (it has: " + key_names(keys_) + ")");
    if (key->kind == KeySpec::Kind::number || key->kind == KeySpec::Kind::integer) parse_spec_number(owner_, name, value, key->range);
    if (key->kind == KeySpec::Kind::choice && choice_meant(*key, value).empty()) {
      throw std::invalid_argument(owner_ + ": " + name + "=" + value + " must be " + alternatives(key->choices));
    }
  }
}

const KeySpec& SpecReader::declared(const std::string& key, KeySpec::Kind kind) const {
  const auto found = std::find_if(keys_.begin(), keys_.end(), [&](const KeySpec& k) { return k.name == key; });
  if (found == keys_.end() || found->kind != kind) throw std::logic_error(owner_ + " reads an undeclared key '" + key + "'");
  return *found;
}

double SpecReader::number(const std::string& key) const {
  const KeySpec& declaration = declared(key, KeySpec::Kind::number);
  const auto it = parameters_.find(key);
  return parse_spec_number(owner_, key, it == parameters_.end() ? declaration.default_value : it->second, declaration.range);
}

long SpecReader::integer(const std::string& key) const {
  const KeySpec& declaration = declared(key, KeySpec::Kind::integer);
  const auto it = parameters_.find(key);
  return static_cast<long>(parse_spec_number(owner_, key, it == parameters_.end() ? declaration.default_value : it->second, declaration.range));
}

std::string SpecReader::choice(const std::string& key) const {
  const KeySpec& declaration = declared(key, KeySpec::Kind::choice);
  const auto it = parameters_.find(key);
  return it == parameters_.end() ? declaration.default_value : choice_meant(declaration, it->second);
}

std::string SpecReader::text(const std::string& key) const {
  const KeySpec& declaration = declared(key, KeySpec::Kind::text);
  const auto it = parameters_.find(key);
  return it == parameters_.end() ? declaration.default_value : it->second;
}

std::string format_spec_number(double value) {
  char text[32];
  const auto [end, error] = std::to_chars(text, text + sizeof(text), value);
  if (error != std::errc()) throw std::logic_error("a double that std::to_chars cannot print in 32 characters");
  return std::string(text, end);
}

double parse_spec_number(const std::string& owner, const std::string& key, const std::string& value, SpecRange range) {
  const std::optional<double> parsed = parse_double(value);
  const double number = parsed.value_or(0.0);
  if (!parsed || !std::isfinite(number) || number < range.minimum || number > range.maximum || (range.integer && number != std::floor(number))) {
    std::ostringstream message;
    message << owner << ": " << key << "=" << value << " must be " << (range.integer ? "an integer" : "a number") << " in ["
            << format_spec_number(range.minimum) << ", " << format_spec_number(range.maximum) << "]";
    throw std::invalid_argument(message.str());
  }
  return number;
}

std::string key_names(const std::vector<KeySpec>& keys) {
  std::string text;
  for (const KeySpec& key : keys) text += (text.empty() ? "" : ", ") + key.name;
  return text.empty() ? "none" : text;
}

std::pair<std::string, SpecParameters> split_spec(const std::string& spec) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  while (true) {
    const std::size_t colon = spec.find(':', begin);
    parts.push_back(spec.substr(begin, colon == std::string::npos ? std::string::npos : colon - begin));
    if (colon == std::string::npos) break;
    begin = colon + 1;
  }
  // A head that names a file (plugin:PATH, answers:DIR, after a strategy's '+' too) keeps the file as its own part.
  std::size_t first_key = 1;
  const std::string& head = parts[0];
  const std::string kind = head.substr(head.find('+') == std::string::npos ? 0 : head.find('+') + 1);
  if (is_file_head(kind)) {
    if (parts.size() < 2 || parts[1].empty()) throw std::invalid_argument("'" + spec + "': " + kind + ": needs a path (" + kind + ":PATH)");
    parts[0] += ":" + parts[1];
    first_key = 2;
  }
  SpecParameters parameters;
  for (std::size_t i = first_key; i < parts.size(); ++i) {
    const std::size_t equals = parts[i].find('=');
    if (equals == std::string::npos || equals == 0) throw std::invalid_argument("'" + parts[i] + "' in '" + spec + "' is not key=value");
    const std::string key = parts[i].substr(0, equals);
    // answers:FILE:method=NAME: a method's name is a resolved spec itself ("cubic64:eta=1e-06", "plugin:PATH:..."),
    // as the file holds it: method= takes the rest of the spec, ':' included, and is its last key.
    if (kind == kAnswersHead && key == "method") {
      std::string rest = parts[i].substr(equals + 1);
      for (std::size_t j = i + 1; j < parts.size(); ++j) rest += ":" + parts[j];
      parameters[key] = rest;
      break;
    }
    parameters[key] = parts[i].substr(equals + 1);
  }
  return {parts[0], parameters};
}

bool is_file_head(const std::string& head) { return head == kPluginHead || head == kAnswersHead || head == kHostMethodHead; }

}  // namespace ccd::narrowphase
