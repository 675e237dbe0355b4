#include "datasets/rational.hpp"

#include <mpfr.h>

#include <string>

namespace ccd::datasets {

RoundedRational round_to_double(const mpq_class& q) {
  // mpfr_set_q rounds correctly to 53 bits but with MPFR's unbounded exponent; restricting the exponent range
  // to double's and subnormalizing makes the one rounding identical to IEEE's (MPFR manual, "Exception Related
  // Functions", the emulation of double). The exponent range is thread-local in Debian's MPFR and is restored.
  const mpfr_exp_t saved_emin = mpfr_get_emin();
  const mpfr_exp_t saved_emax = mpfr_get_emax();
  mpfr_set_emin(-1073);
  mpfr_set_emax(1024);
  mpfr_t x;
  mpfr_init2(x, 53);
  int ternary = mpfr_set_q(x, q.get_mpq_t(), MPFR_RNDN);
  ternary = mpfr_check_range(x, ternary, MPFR_RNDN);
  ternary = mpfr_subnormalize(x, ternary, MPFR_RNDN);
  const double value = mpfr_get_d(x, MPFR_RNDN);
  mpfr_clear(x);
  mpfr_set_emin(saved_emin);
  mpfr_set_emax(saved_emax);
  return {value, ternary == 0};
}

std::optional<mpz_class> parse_integer(std::string_view text) {
  std::size_t digits_from = (!text.empty() && text.front() == '-') ? 1 : 0;
  if (text.size() == digits_from) return std::nullopt;
  for (std::size_t i = digits_from; i < text.size(); ++i) {
    if (text[i] < '0' || text[i] > '9') return std::nullopt;
  }
  mpz_class value;
  if (value.set_str(std::string(text), 10) != 0) return std::nullopt;
  return value;
}

}  // namespace ccd::datasets
