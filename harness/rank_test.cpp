#include "harness/rank_test.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace ccd::harness {
namespace {

/// The number of rankings of n x's and m y's with each U = 0 .. n*m (no ties): the recurrence
/// c(n, m, u) = c(n - 1, m, u - m) + c(n, m - 1, u) of Mann and Whitney (1947), in doubles (exact up to 2^53).
std::vector<double> u_counts(std::size_t n, std::size_t m) {
  // counts[i][j] for the current n: the distribution of U for samples of sizes (i, j), built up row by row.
  std::vector<std::vector<std::vector<double>>> table(n + 1, std::vector<std::vector<double>>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) {
    for (std::size_t j = 0; j <= m; ++j) {
      std::vector<double>& here = table[i][j];
      here.assign(i * j + 1, 0.0);
      if (i == 0 || j == 0) {
        here[0] = 1;
        continue;
      }
      // The largest value is an x (its j y's below it: U grows by j) or a y (U unchanged).
      for (std::size_t u = 0; u <= i * j; ++u) {
        if (u >= j && u - j < table[i - 1][j].size()) here[u] += table[i - 1][j][u - j];
        if (u < table[i][j - 1].size()) here[u] += table[i][j - 1][u];
      }
    }
  }
  return table[n][m];
}

}  // namespace

RankTest mann_whitney(const std::vector<double>& x, const std::vector<double>& y) {
  RankTest result;
  const std::size_t n = x.size(), m = y.size();
  if (n == 0 || m == 0) return result;
  bool ties = false;
  for (double a : x) {
    for (double b : y) {
      result.u += a > b ? 1.0 : a == b ? 0.5 : 0.0;
      ties = ties || a == b;
    }
  }
  std::vector<double> all(x);
  all.insert(all.end(), y.begin(), y.end());
  std::sort(all.begin(), all.end());
  for (std::size_t k = 1; k < all.size() && !ties; ++k) ties = all[k] == all[k - 1];
  const double mean = static_cast<double>(n * m) / 2;
  const double distance = std::abs(result.u - mean);
  if (!ties && n * m <= 400) {
    const std::vector<double> counts = u_counts(n, m);
    const double total = std::accumulate(counts.begin(), counts.end(), 0.0);
    double extreme = 0;
    for (std::size_t u = 0; u < counts.size(); ++u) {
      if (std::abs(static_cast<double>(u) - mean) >= distance - 1e-9) extreme += counts[u];
    }
    result.p = std::min(1.0, extreme / total);
    return result;
  }
  // Normal approximation: the variance of U with the correction for tied groups (t^3 - t over each group).
  double tie_term = 0;
  for (std::size_t k = 0; k < all.size();) {
    std::size_t j = k;
    while (j < all.size() && all[j] == all[k]) ++j;
    const double t = static_cast<double>(j - k);
    tie_term += t * t * t - t;
    k = j;
  }
  const double total = static_cast<double>(n + m);
  const double variance = static_cast<double>(n * m) / 12.0 * ((total + 1) - tie_term / (total * (total - 1)));
  if (variance <= 0) return result;  // every value equal: no evidence of a difference
  const double z = std::max(0.0, distance - 0.5) / std::sqrt(variance);
  result.p = std::min(1.0, std::erfc(z / std::sqrt(2.0)));
  return result;
}

}  // namespace ccd::harness
