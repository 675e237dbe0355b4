#pragma once
/// @file
/// Numbers read from text (spec keys, flags, settings) the same way whatever the process's C locale: a program that
/// calls setlocale (a Python script's `locale.setlocale(locale.LC_ALL, "")`, or code under audit) must not make
/// "0.25" unreadable, as std::stod and strtod would under a locale whose decimal point is ','.

#include <charconv>
#include <optional>
#include <string_view>
#include <system_error>

namespace ccd {

/// The whole of `text` as a double (decimal or scientific, an optional leading '+' or '-', "inf" and "nan" as
/// std::from_chars reads them), or nullopt when it is not one or is out of the range of double.
inline std::optional<double> parse_double(std::string_view text) {
  if (text.size() > 1 && text.front() == '+' && text[1] != '-' && text[1] != '+') text.remove_prefix(1);
  double value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value, std::chars_format::general);
  if (error != std::errc() || end != text.data() + text.size() || text.empty()) return std::nullopt;
  return value;
}

}  // namespace ccd
