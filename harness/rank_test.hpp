#pragma once
/// @file
/// Rank tests of run times. The Mann-Whitney U test (Wilcoxon rank-sum), two-sided: whether two samples of times come from one distribution,
/// the test Google Benchmark's compare.py applies to repetitions. It assumes neither sample normal, which run times
/// are not (a noisy machine adds a long tail), and is exact for the few repeats a run has. Written here because no
/// Debian C++ library the project uses has it (Boost.Math and GSL do not); it is short and tested against published
/// tables (tests/harness/compare_test.cpp).

#include <vector>

namespace ccd::harness {

struct RankTest {
  /// U of the first sample: how many (x, y) pairs have x > y, ties counting one half.
  double u = 0;
  /// The two-sided p-value: the probability, were both samples from one distribution, of a U at least as far from
  /// its mean n*m/2. Exact (from the distribution of U over every ranking) without ties and for n*m <= 400; else the
  /// normal approximation with the tie correction and a continuity correction. 1 when a sample is empty.
  double p = 1;
};

RankTest mann_whitney(const std::vector<double>& x, const std::vector<double>& y);

/// The Wilcoxon signed-rank test, two-sided, of paired samples: whether y[i] / x[i] is centred on 1 (the logs of
/// the ratios ranked by size, zero differences left out, as Wilcoxon did). For two cells whose passes ran in turn
/// (`run --interleave`): a drift of the machine moves both members of a pair, so the test sees the change alone.
/// `u` is W+, the sum of the ranks of the pairs where y is larger. Exact (the distribution of W+ over every sign
/// assignment) without tied sizes and for up to 60 pairs; else the normal approximation with the tie correction and a
/// continuity correction. 1 when no pair differs. Throws std::invalid_argument when the sizes differ or a time is not
/// positive.
RankTest wilcoxon_signed_rank(const std::vector<double>& x, const std::vector<double>& y);

/// The smallest two-sided p-value the exact signed-rank test can give for n pairs: 2 / 2^n.
double smallest_signed_rank_p(std::size_t n);

/// Holm's step-down adjustment of p-values for a family of tests (Holm 1979): each p multiplied by the number of
/// tests not yet rejected, made monotone; a test is rejected at family-wise level alpha when its adjusted p < alpha.
/// The chance that any test of the family calls a difference where there is none is then at most alpha, whatever
/// the family's size.
std::vector<double> holm_adjusted(const std::vector<double>& p);

}  // namespace ccd::harness
