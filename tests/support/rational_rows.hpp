#pragma once
/// @file
/// Prints a query in the rational query format (numerator,denominator per coordinate, 8 rows), so a failing
/// case can be pasted into a regression file as it is.

#include "core/vec.hpp"

#include <gmpxx.h>

#include <array>
#include <string>

namespace ccd::testing {

inline std::string rational_rows(const std::array<Vec3, 8>& rows, int truth = -1) {
  std::string text;
  for (const Vec3& row : rows) {
    for (int k = 0; k < 3; ++k) {
      const mpq_class q(row[k]);
      text += q.get_num().get_str() + "," + q.get_den().get_str() + (k < 2 || truth >= 0 ? "," : "");
    }
    if (truth >= 0) text += std::to_string(truth);
    text += "\n";
  }
  return text;
}

}  // namespace ccd::testing
