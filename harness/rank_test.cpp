#include "harness/rank_test.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

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

RankTest wilcoxon_signed_rank(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size())
    throw std::invalid_argument("a signed-rank test needs pairs: " + std::to_string(x.size()) + " and " + std::to_string(y.size()));
  std::vector<double> differences;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (!(x[i] > 0) || !(y[i] > 0)) throw std::invalid_argument("a signed-rank test of ratios needs positive times");
    const double d = std::log(y[i]) - std::log(x[i]);
    if (d != 0) differences.push_back(d);
  }
  RankTest result;
  const std::size_t n = differences.size();
  if (n == 0) return result;
  std::sort(differences.begin(), differences.end(), [](double a, double b) { return std::abs(a) < std::abs(b); });
  // Ranks of the sizes, tied sizes sharing their mean rank.
  bool ties = false;
  double tie_term = 0;
  for (std::size_t k = 0; k < n;) {
    std::size_t j = k;
    while (j < n && std::abs(differences[j]) == std::abs(differences[k])) ++j;
    const double rank = (static_cast<double>(k + 1) + static_cast<double>(j)) / 2;
    for (std::size_t i = k; i < j; ++i) result.u += differences[i] > 0 ? rank : 0.0;
    const double t = static_cast<double>(j - k);
    tie_term += t * t * t - t;
    ties = ties || j - k > 1;
    k = j;
  }
  const double mean = static_cast<double>(n * (n + 1)) / 4;
  const double distance = std::abs(result.u - mean);
  if (!ties && n <= 60) {
    // counts[w]: the sign assignments of ranks 1..n whose positive ranks add up to w (each rank in or out).
    std::vector<double> counts(n * (n + 1) / 2 + 1, 0.0);
    counts[0] = 1;
    for (std::size_t rank = 1; rank <= n; ++rank) {
      for (std::size_t w = counts.size() - 1; w >= rank; --w) counts[w] += counts[w - rank];
    }
    const double total = std::ldexp(1.0, static_cast<int>(n));
    double extreme = 0;
    for (std::size_t w = 0; w < counts.size(); ++w) {
      if (std::abs(static_cast<double>(w) - mean) >= distance - 1e-9) extreme += counts[w];
    }
    result.p = std::min(1.0, extreme / total);
    return result;
  }
  const double variance = static_cast<double>(n * (n + 1) * (2 * n + 1)) / 24 - tie_term / 48;
  if (variance <= 0) return result;
  const double z = std::max(0.0, distance - 0.5) / std::sqrt(variance);
  result.p = std::min(1.0, std::erfc(z / std::sqrt(2.0)));
  return result;
}

double smallest_signed_rank_p(std::size_t n) { return std::min(1.0, 2.0 / std::ldexp(1.0, static_cast<int>(std::min<std::size_t>(n, 1000)))); }

std::vector<double> holm_adjusted(const std::vector<double>& p) {
  std::vector<std::size_t> order(p.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return p[a] < p[b]; });
  std::vector<double> adjusted(p.size());
  double running = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    running = std::max(running, std::min(1.0, static_cast<double>(p.size() - k) * p[order[k]]));
    adjusted[order[k]] = running;
  }
  return adjusted;
}

}  // namespace ccd::harness
