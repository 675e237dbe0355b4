#include "datasets/rational.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace ccd::datasets {
namespace {

TEST(RoundToDouble, ExactValuesAreFlaggedExact) {
  const auto half = round_to_double(mpq_class(1, 2));
  EXPECT_EQ(half.value, 0.5);
  EXPECT_TRUE(half.exact);
  const auto big = round_to_double(mpq_class(mpz_class("-8388607"), mpz_class("8388608")));
  EXPECT_EQ(big.value, -8388607.0 / 8388608.0);
  EXPECT_TRUE(big.exact);
}

TEST(RoundToDouble, InexactValuesRoundToNearest) {
  const auto third = round_to_double(mpq_class(1, 3));
  EXPECT_EQ(third.value, 1.0 / 3.0);
  EXPECT_FALSE(third.exact);
  const auto tenth = round_to_double(mpq_class(-1, 10));
  EXPECT_EQ(tenth.value, -0.1);
}

TEST(RoundToDouble, TiesGoToEven) {
  // 1 + 2^-53 lies halfway between 1 and 1 + 2^-52: the even neighbour is 1.
  mpq_class halfway(1);
  halfway += mpq_class(1, mpz_class(1) << 53);
  EXPECT_EQ(round_to_double(halfway).value, 1.0);
  // 1 + 3·2^-53 lies halfway between 1 + 2^-52 and 1 + 2^-51: the even one is 1 + 2^-51.
  mpq_class upper(1);
  upper += mpq_class(3, mpz_class(1) << 53);
  EXPECT_EQ(round_to_double(upper).value, 1.0 + std::ldexp(1.0, -51));
}

TEST(RoundToDouble, SubnormalsRoundOnceAndOverflowIsInfinite) {
  const double tiny = std::numeric_limits<double>::denorm_min();
  mpq_class three_halves_tiny(3, mpz_class(1) << 1075);  // 1.5 × 2^-1074: ties to even, 2 × 2^-1074
  EXPECT_EQ(round_to_double(three_halves_tiny).value, 2 * tiny);
  mpq_class quarter_tiny(1, mpz_class(1) << 1076);
  EXPECT_EQ(round_to_double(quarter_tiny).value, 0.0);
  const auto huge = round_to_double(mpq_class(mpz_class(1) << 1024));
  EXPECT_TRUE(std::isinf(huge.value));
  EXPECT_FALSE(huge.exact);
}

TEST(ParseInteger, AcceptsOnlyPlainBaseTenIntegers) {
  EXPECT_EQ(*parse_integer("-123456789012345678901234567890"), mpz_class("-123456789012345678901234567890"));
  EXPECT_FALSE(parse_integer("").has_value());
  EXPECT_FALSE(parse_integer("-").has_value());
  EXPECT_FALSE(parse_integer("+1").has_value());
  EXPECT_FALSE(parse_integer("1.5").has_value());
  EXPECT_FALSE(parse_integer("1 2").has_value());
}

}  // namespace
}  // namespace ccd::datasets
