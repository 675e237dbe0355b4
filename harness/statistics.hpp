#pragma once
/// @file
/// The one statistic the harness reports times with.

#include <algorithm>
#include <vector>

namespace ccd::harness {

/// The median (mean of the two middle values for an even count); 0 for no values.
inline double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : (values[n / 2 - 1] + values[n / 2]) / 2;
}

}  // namespace ccd::harness
