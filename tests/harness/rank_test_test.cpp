// The rank tests compare's time verdicts use (harness/rank_test.hpp), against published and R's values.

#include "harness/rank_test.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

namespace ccd {
namespace {

// Published values: the two-sample example of R's wilcox.test (Hollander and Wolfe), exact; exact tables for small
// samples (the two most extreme of C(n + m, n) rankings); and, with ties, the normal approximation with the tie
// correction and a continuity correction as textbooks state it (computed by hand for these samples).
TEST(RankTest, ExactPValuesMatchPublishedValues) {
  const harness::RankTest r = harness::mann_whitney({0.80, 0.83, 1.89, 1.04, 1.45, 1.38, 1.91, 1.64, 0.73, 1.46}, {1.15, 0.88, 0.90, 0.74, 1.21});
  EXPECT_EQ(r.u, 35);
  EXPECT_NEAR(r.p, 0.2544122544, 1e-9);  // R: W = 35, p-value = 0.1272 one-sided
  EXPECT_NEAR(harness::mann_whitney({1, 2, 3, 4, 5}, {6, 7, 8, 9, 10}).p, 2.0 / 252, 1e-12);
  EXPECT_NEAR(harness::mann_whitney({1, 2, 3}, {4, 5, 6}).p, 2.0 / 20, 1e-12);
  EXPECT_NEAR(harness::mann_whitney({1, 2, 3, 5}, {4, 6, 7, 8}).p, 4.0 / 70, 1e-12);
  EXPECT_EQ(harness::mann_whitney({1, 2, 3, 5}, {4, 6, 7, 8}).u, 1);
  EXPECT_EQ(harness::mann_whitney({}, {1, 2}).p, 1);
}

// The signed-rank test of the logs of paired ratios (R: wilcox.test(log(y), log(x), paired = TRUE)), and Holm's
// adjustment (R: p.adjust(p, "holm")).
TEST(RankTest, SignedRanksAndHolmMatchR) {
  const harness::RankTest five = harness::wilcoxon_signed_rank({1, 1, 1, 1, 1}, {1.1, 1.2, 0.7, 1.4, 1.5});
  EXPECT_EQ(five.u, 11);                  // V = 11
  EXPECT_NEAR(five.p, 14.0 / 32, 1e-12);  // p-value = 0.4375
  std::vector<double> x(9, 10.0), y(9, 12.5);
  for (std::size_t i = 0; i < 9; ++i) y[i] += 0.1 * static_cast<double>(i);
  EXPECT_NEAR(harness::wilcoxon_signed_rank(x, y).p, 2.0 / 512, 1e-12);
  EXPECT_NEAR(harness::smallest_signed_rank_p(9), 2.0 / 512, 1e-12);
  EXPECT_EQ(harness::wilcoxon_signed_rank({1, 2}, {1, 2}).p, 1);  // no pair differs
  EXPECT_THROW(harness::wilcoxon_signed_rank({1, 2}, {1}), std::invalid_argument);
  const std::vector<double> adjusted = harness::holm_adjusted({0.01, 0.04, 0.03, 0.005});
  const std::vector<double> expected = {0.03, 0.06, 0.06, 0.02};
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_NEAR(adjusted[i], expected[i], 1e-12) << i;
}

TEST(RankTest, TiesUseTheCorrectedNormalApproximation) {
  std::vector<double> x, y;
  for (int k = 0; k < 30; ++k) {
    x.push_back(k);
    y.push_back(k + 10);
  }
  EXPECT_NEAR(harness::mann_whitney(x, y).p, 0.00022448380595775665, 1e-12);
  EXPECT_NEAR(harness::mann_whitney({1, 2, 2, 3, 3, 3, 4, 5}, {3, 4, 4, 5, 6, 6, 7}).p, 0.01598468512519625, 1e-12);
  EXPECT_EQ(harness::mann_whitney({2, 2, 2}, {2, 2}).p, 1);
}

}  // namespace
}  // namespace ccd
