#pragma once
/// @file
/// The statistics the harness reports: the median of times, and percentiles of errors.

#include <algorithm>
#include <cmath>
#include <vector>

namespace ccd::harness {

/// The median (mean of the two middle values for an even count); 0 for no values.
inline double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : (values[n / 2 - 1] + values[n / 2]) / 2;
}

/// The nearest-rank percentile (0 < p <= 100): the smallest value that at least p% of the values are no greater
/// than, so it is always one of the values (p = 100: the largest); 0 for no values.
inline double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  const double rank = std::ceil(p / 100.0 * static_cast<double>(values.size()));
  const std::size_t index = static_cast<std::size_t>(std::clamp(rank, 1.0, static_cast<double>(values.size()))) - 1;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index), values.end());
  return values[index];
}

}  // namespace ccd::harness
