#pragma once
/// @file
/// The Mann-Whitney U test (Wilcoxon rank-sum), two-sided: whether two samples of times come from one distribution,
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

}  // namespace ccd::harness
