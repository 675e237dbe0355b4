#pragma once
/// @file
/// Univariate polynomials in t with exact rational coefficients: the scalar with which the sign conditions are
/// expanded into the polynomials the exact path isolates. Degrees stay <= 6 here, so dense coefficient vectors
/// and schoolbook multiplication are the simplest correct choice.

#include <gmpxx.h>

#include <vector>

namespace ccd::reference {

class RationalPolynomial {
 public:
  RationalPolynomial() = default;
  /// The constant c.
  RationalPolynomial(mpq_class c);  // NOLINT: implicit, so constants mix with polynomials in the formulas
  /// c0 + c1·t.
  static RationalPolynomial linear(const mpq_class& c0, const mpq_class& c1);

  /// Coefficients from degree 0 up; no trailing zeros (the zero polynomial has none).
  const std::vector<mpq_class>& coefficients() const { return coefficients_; }
  bool is_zero() const { return coefficients_.empty(); }
  int degree() const { return static_cast<int>(coefficients_.size()) - 1; }
  mpq_class evaluate(const mpq_class& t) const;

  friend RationalPolynomial operator+(const RationalPolynomial& a, const RationalPolynomial& b);
  friend RationalPolynomial operator-(const RationalPolynomial& a, const RationalPolynomial& b);
  friend RationalPolynomial operator*(const RationalPolynomial& a, const RationalPolynomial& b);

 private:
  void trim();
  std::vector<mpq_class> coefficients_;
};

inline RationalPolynomial square(const RationalPolynomial& a) { return a * a; }

}  // namespace ccd::reference
