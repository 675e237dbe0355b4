#include "reference/rational_polynomial.hpp"

#include <algorithm>

namespace ccd::reference {

RationalPolynomial::RationalPolynomial(mpq_class c) {
  coefficients_.push_back(std::move(c));
  trim();
}

RationalPolynomial RationalPolynomial::linear(const mpq_class& c0, const mpq_class& c1) {
  RationalPolynomial p;
  p.coefficients_ = {c0, c1};
  p.trim();
  return p;
}

void RationalPolynomial::trim() {
  while (!coefficients_.empty() && sgn(coefficients_.back()) == 0) coefficients_.pop_back();
}

mpq_class RationalPolynomial::evaluate(const mpq_class& t) const {
  mpq_class value = 0;
  for (auto it = coefficients_.rbegin(); it != coefficients_.rend(); ++it) value = value * t + *it;
  return value;
}

RationalPolynomial operator+(const RationalPolynomial& a, const RationalPolynomial& b) {
  RationalPolynomial sum;
  sum.coefficients_.resize(std::max(a.coefficients_.size(), b.coefficients_.size()));
  for (std::size_t i = 0; i < sum.coefficients_.size(); ++i) {
    if (i < a.coefficients_.size()) sum.coefficients_[i] += a.coefficients_[i];
    if (i < b.coefficients_.size()) sum.coefficients_[i] += b.coefficients_[i];
  }
  sum.trim();
  return sum;
}

RationalPolynomial operator-(const RationalPolynomial& a, const RationalPolynomial& b) {
  RationalPolynomial difference;
  difference.coefficients_.resize(std::max(a.coefficients_.size(), b.coefficients_.size()));
  for (std::size_t i = 0; i < difference.coefficients_.size(); ++i) {
    if (i < a.coefficients_.size()) difference.coefficients_[i] += a.coefficients_[i];
    if (i < b.coefficients_.size()) difference.coefficients_[i] -= b.coefficients_[i];
  }
  difference.trim();
  return difference;
}

RationalPolynomial operator*(const RationalPolynomial& a, const RationalPolynomial& b) {
  RationalPolynomial product;
  if (a.is_zero() || b.is_zero()) return product;
  product.coefficients_.assign(a.coefficients_.size() + b.coefficients_.size() - 1, mpq_class(0));
  for (std::size_t i = 0; i < a.coefficients_.size(); ++i) {
    for (std::size_t j = 0; j < b.coefficients_.size(); ++j) product.coefficients_[i + j] += a.coefficients_[i] * b.coefficients_[j];
  }
  product.trim();
  return product;
}

}  // namespace ccd::reference
