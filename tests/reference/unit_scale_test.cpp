// The reference decides a pair brought to unit size by a power of two (reference/unit_scale.hpp, issue 60): the
// same answer, TOI and way of deciding at every exact scale, and the exact answer also where bringing a pair of
// doubles to unit size loses bits (coordinates spanning more than double's range).

#include "reference/unit_scale.hpp"
#include "reference/elementary_pair.hpp"
#include "tests/support/rational_rows.hpp"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <optional>

namespace ccd::reference {
namespace {

const double kSmallestSubnormal = std::ldexp(1.0, -1074);
const double kHuge = std::ldexp(1.0, 1022);  // DBL_MAX is just below 2^1024; 4 times this would overflow

/// A triangle near DBL_MAX in size (its normal's terms overflow double), in the plane z = 0, static, and a vertex
/// over its middle at heights z0 and z1 (subnormal): brought to unit size (2^-1022), the heights fall below the
/// smallest subnormal.
std::array<Vec3, 8> huge_face_and_subnormal_vertex(double z0, double z1) {
  const Vec3 a(-kHuge, -kHuge, 0), b(kHuge, -kHuge, 0), c(0, kHuge, 0);
  return {Vec3(0, 0, z0), a, b, c, Vec3(0, 0, z1), a, b, c};
}

/// A static edge along x near DBL_MAX in length, and an edge along y of subnormal length at heights z0 and z1.
std::array<Vec3, 8> huge_edge_and_subnormal_edge(double z0, double z1) {
  const Vec3 a0(-kHuge, 0, 0), a1(kHuge, 0, 0);
  const double s = kSmallestSubnormal;
  return {a0, a1, Vec3(0, -s, z0), Vec3(0, s, z0), a0, a1, Vec3(0, -s, z1), Vec3(0, s, z1)};
}

struct SpanCase {
  std::string name;
  PairKind kind;
  std::array<Vec3, 8> rows;
  double thickness;
  bool collides;
  /// With collides: the exact earliest contact, a double, asked for (the exact path then decides).
  std::optional<double> toi;
  /// Also through the rationals' entry (the filter's intervals from MPFR).
  bool also_rationals = false;
};

/// Exact decisions of such pairs take 10 to 40 ms each (3 times that under the sanitizers): at unit size their
/// rationals run from 2 down to 2^-2096. So each case is decided once, a few of them through both entries.
void expect_exact_answer(const SpanCase& c) {
  const std::string described = c.name + ", δ = " + std::to_string(c.thickness) + ":\n" + testing::rational_rows(c.rows, c.collides ? 1 : 0);
  const Decision on_doubles = decide(c.kind, c.rows, c.thickness, {true, c.toi.has_value(), 64});
  EXPECT_EQ(on_doubles.collides, c.collides) << "doubles: " << described;
  if (c.toi) {
    EXPECT_EQ(on_doubles.toi_floor, c.toi) << described;
    EXPECT_EQ(on_doubles.toi_ceiling, c.toi) << described;
  }
  if (c.also_rationals) {
    EXPECT_EQ(decide(exact_pair_from_doubles(c.kind, c.rows), mpq_class(c.thickness)).collides, c.collides) << "rationals: " << described;
  }
}

// Brought to unit size, the subnormal heights become smaller than any double: a reference that took them as the
// nearest doubles (zero) would put the vertex on the face from the start (and the edges on each other).
TEST(UnitScale, PairsSpanningMoreThanDoublesRangeKeepTheirExactAnswers) {
  const double s = kSmallestSubnormal;
  ASSERT_NE(unit_scale_exponent(huge_face_and_subnormal_vertex(s, s), 0.0), 0);
  ASSERT_EQ(std::ldexp(s, -unit_scale_exponent(huge_face_and_subnormal_vertex(s, s), 0.0)), 0.0);
  const std::vector<SpanCase> cases = {
      {"vertex a subnormal above a huge face", PairKind::vertex_face, huge_face_and_subnormal_vertex(s, 2 * s), 0.0, false, std::nullopt},
      {"vertex a subnormal above a huge face, within δ", PairKind::vertex_face, huge_face_and_subnormal_vertex(s, 2 * s), s, true, std::nullopt},
      {"vertex crossing a huge face late", PairKind::vertex_face, huge_face_and_subnormal_vertex(3 * s, -s), 0.0, true, 0.75},
      {"subnormal edge above a huge edge", PairKind::edge_edge, huge_edge_and_subnormal_edge(s, s), 0.0, false, std::nullopt, true},
  };
  for (const SpanCase& c : cases) expect_exact_answer(c);
}

// Boundary: a double whose product with 2^-1 lies half a subnormal step below DBL_MIN rounds up to DBL_MIN itself
// (ties to even), so reaching DBL_MIN does not prove a product exact. The filter's interval must still hold the exact
// product, as it does one step either side.
TEST(UnitScale, ProductsRoundedUpToTheNormalRangeAreEnclosed) {
  const double just_below = std::nextafter(std::ldexp(DBL_MIN, 1), 0.0);  // (2 - 2^-52)·2^-1022
  for (double v : {std::nextafter(just_below, 0.0), just_below, std::ldexp(DBL_MIN, 1)}) {
    std::array<Vec3, 8> rows;
    rows.fill(Vec3::Zero());  // Eigen's vectors start uninitialized
    rows[0] = Vec3(v, 2, 0);  // the largest, 2, sets the exponent 1
    ASSERT_EQ(unit_scale_exponent(rows, 0.0), 1);
    const Interval x = scaled_intervals(rows, 0.0, 1).rows[0].x;
    const mpq_class exact = mpq_class(v) / 2;
    EXPECT_LE(mpq_class(x.inf()), exact) << std::hexfloat << v;
    EXPECT_GE(mpq_class(x.sup()), exact) << std::hexfloat << v;
  }
}

/// A VF pair crossing its face at t = 1/2, an EE pair missing by 1/4, a VF pair touching within δ at its start.
std::vector<std::tuple<PairKind, std::array<Vec3, 8>, double>> small_cases() {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  return {{PairKind::vertex_face, {Vec3(0.25, 0.25, 1), a, b, c, Vec3(0.25, 0.25, -1), a, b, c}, 0.0},
          {PairKind::edge_edge,
           {Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, -1, 0.25), Vec3(0, 1, 0.25), Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, -1, 0.25), Vec3(0, 1, 0.25)},
           0.125},
          {PairKind::vertex_face, {Vec3(0.25, 0.25, 0.0625), a, b, c, Vec3(0.25, 0.25, 2), a, b, c}, 0.125}};
}

// The pair at 2^-1000 and 2^1000 is the same numbers brought to unit size as at 2^0: the same answer, TOI and way
// of deciding (the filter underflowed or overflowed there before, and left the pair to the exact path).
TEST(UnitScale, TheSameDecisionAtEveryExactScale) {
  for (const auto& [kind, rows, thickness] : small_cases()) {
    for (bool want_toi : {false, true}) {
      const Decision unit = decide(kind, rows, thickness, {true, want_toi, 64});
      for (int exponent : {-1000, 1000}) {
        std::array<Vec3, 8> scaled = rows;
        for (Vec3& row : scaled) row *= std::ldexp(1.0, exponent);
        const Decision at_scale = decide(kind, scaled, std::ldexp(thickness, exponent), {true, want_toi, 64});
        const std::string described =
            "at 2^" + std::to_string(exponent) + ", δ = " + std::to_string(thickness) + ":\n" + testing::rational_rows(rows, -1);
        EXPECT_EQ(at_scale.collides, unit.collides) << described;
        EXPECT_EQ(at_scale.decided_by, unit.decided_by) << described;
        EXPECT_EQ(at_scale.toi_floor, unit.toi_floor) << described;
        EXPECT_EQ(at_scale.toi_ceiling, unit.toi_ceiling) << described;
      }
    }
  }
}

}  // namespace
}  // namespace ccd::reference
