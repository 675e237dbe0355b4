#include "reference/unit_scale.hpp"

#include <cfloat>
#include <climits>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ccd::reference {

namespace {

/// ⌊log2 |q|⌋ for q ≠ 0 written p/d in lowest terms, up to one: |p| lies in [2^(a-1), 2^a) and d in [2^(b-1), 2^b)
/// (a, b their bit counts), so |q| lies in (2^(a-b-1), 2^(a-b+1)). For a double (d a power of two) a - b is
/// ⌊log2 |q|⌋ exactly, its ilogb. Multiplying q by 2^k moves k factors of two between p and d and changes a - b by
/// exactly k.
long bit_count_difference(const mpq_class& q) {
  return static_cast<long>(mpz_sizeinbase(q.get_num_mpz_t(), 2)) - static_cast<long>(mpz_sizeinbase(q.get_den_mpz_t(), 2));
}

/// v·2^-exponent, given `factor` = 2^-exponent when that is a normal double (0 otherwise).
Interval scaled_interval(double v, double factor, int exponent) {
  if (factor != 0) {
    const double scaled = v * factor;
    // The product of a double and a power of two has v's significand: exact wherever it is a normal double. Above
    // DBL_MIN, not at it: a product just below DBL_MIN may round up to it.
    if (std::abs(scaled) > DBL_MIN || v == 0) return Interval(scaled);
  }
  const double scaled = std::ldexp(v, -exponent);
  // Scaling back up is exact, so this tells whether bits were lost. When they were, `scaled` is one of the two
  // doubles around the exact product, whatever the rounding mode, so its neighbours enclose it.
  if (std::ldexp(scaled, exponent) == v) return Interval(scaled);
  return Interval(std::nextafter(scaled, -std::numeric_limits<double>::infinity()), std::nextafter(scaled, std::numeric_limits<double>::infinity()));
}

void scale(mpq_class& q, int exponent) {
  if (exponent > 0) {
    mpq_div_2exp(q.get_mpq_t(), q.get_mpq_t(), static_cast<mp_bitcnt_t>(exponent));
  } else if (exponent < 0) {
    mpq_mul_2exp(q.get_mpq_t(), q.get_mpq_t(), static_cast<mp_bitcnt_t>(-exponent));
  }
}

}  // namespace

int unit_scale_exponent(const std::array<Vec3, 8>& rows, double thickness) {
  double largest = std::abs(thickness);
  bool finite = std::isfinite(thickness);
  for (const Vec3& row : rows) {
    for (int k = 0; k < 3; ++k) {
      finite = finite && std::isfinite(row[k]);
      largest = std::max(largest, std::abs(row[k]));
    }
  }
  // GMP raises SIGFPE on a non-finite double: refuse it as an argument error instead.
  if (!finite) throw std::invalid_argument("reference: a coordinate or δ is not finite");
  return largest == 0 ? 0 : std::ilogb(largest);
}

int unit_scale_exponent(const ExactPair& pair, const mpq_class& thickness) {
  long largest = LONG_MIN;
  if (sgn(thickness) != 0) largest = bit_count_difference(thickness);
  for (const RationalPoint& row : pair.rows) {
    for (const mpq_class& q : row) {
      if (sgn(q) != 0) largest = std::max(largest, bit_count_difference(q));
    }
  }
  if (largest == LONG_MIN) return 0;
  if (largest > INT_MAX / 2 || largest < INT_MIN / 2) throw std::invalid_argument("reference: a coordinate or δ is beyond 2^±(2^30)");
  return static_cast<int>(largest);
}

ScaledIntervals scaled_intervals(const std::array<Vec3, 8>& rows, double thickness, int exponent) {
  // 2^-exponent is a normal double for |exponent| <= 1022; only pairs whose largest value is 2^1023 or more, or
  // subnormal, take ldexp for every value.
  const double factor = std::abs(exponent) <= 1022 ? std::ldexp(1.0, -exponent) : 0.0;
  ScaledIntervals out;
  for (int r = 0; r < 8; ++r) {
    out.rows[r] = {scaled_interval(rows[r].x(), factor, exponent), scaled_interval(rows[r].y(), factor, exponent),
                   scaled_interval(rows[r].z(), factor, exponent)};
  }
  out.thickness = scaled_interval(thickness, factor, exponent);
  return out;
}

ScaledIntervals scaled_intervals(const ExactPair& pair, const mpq_class& thickness, int exponent) {
  ScaledIntervals out;
  for (int r = 0; r < 8; ++r) {
    out.rows[r] = {enclosing_interval(pair.rows[r][0], -exponent), enclosing_interval(pair.rows[r][1], -exponent),
                   enclosing_interval(pair.rows[r][2], -exponent)};
  }
  out.thickness = enclosing_interval(thickness, -exponent);
  return out;
}

std::pair<ExactPair, mpq_class> scaled_exactly(ExactPair pair, mpq_class thickness, int exponent) {
  for (RationalPoint& row : pair.rows) {
    for (mpq_class& q : row) scale(q, exponent);
  }
  scale(thickness, exponent);
  return {std::move(pair), std::move(thickness)};
}

}  // namespace ccd::reference
