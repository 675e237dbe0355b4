#include "reference/exact_pair.hpp"

#include <stdexcept>

namespace ccd::reference {

ExactPair exact_pair_from_doubles(PairKind kind, const std::array<Vec3, 8>& rows) {
  // GMP raises SIGFPE on a non-finite double: refuse it as an argument error instead.
  for (const Vec3& row : rows) {
    if (!row.allFinite()) throw std::invalid_argument("reference: a coordinate is not finite");
  }
  ExactPair pair;
  pair.kind = kind;
  for (int r = 0; r < 8; ++r) {
    for (int k = 0; k < 3; ++k) pair.rows[r][k] = mpq_class(rows[r][k]);  // exact: every double is a rational
  }
  return pair;
}

}  // namespace ccd::reference
