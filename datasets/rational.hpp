#pragma once
/// @file
/// Exact rationals from the query format and the doubles they round to.

#include <gmpxx.h>

#include <optional>
#include <string_view>

namespace ccd::datasets {

/// The double nearest to a rational (ties to even, subnormals rounded once, as IEEE 754 does), and whether it
/// equals the rational exactly.
struct RoundedRational {
  double value;
  bool exact;
};

/// @return the correctly rounded double; value is ±infinity when |q| exceeds the double range (exact = false).
RoundedRational round_to_double(const mpq_class& q);

/// Parses a base-10 integer ("-12", "8388608"; any length). nullopt for anything else (empty, '+', spaces inside).
std::optional<mpz_class> parse_integer(std::string_view text);

}  // namespace ccd::datasets
