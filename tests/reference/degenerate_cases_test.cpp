// The named library of degenerate cases with known answers (docs/STYLE.md "Tests"). Every case runs three ways:
// exact only, filter then exact, and the filter alone (which may be inconclusive, never wrong).

#include "reference/certified_filter.hpp"
#include "reference/elementary_pair.hpp"
#include "tests/support/rational_rows.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace ccd::reference {
namespace {

struct NamedCase {
  std::string name;
  PairKind kind;
  std::array<Vec3, 8> rows;
  double thickness;
  bool collides;
  /// When set: the earliest contact time, which the returned TOI interval must contain.
  std::optional<double> toi;
};

/// A VF case from the point and triangle at t0 and t1.
std::array<Vec3, 8> vf(Vec3 p0, Vec3 a0, Vec3 b0, Vec3 c0, Vec3 p1, Vec3 a1, Vec3 b1, Vec3 c1) { return {p0, a0, b0, c0, p1, a1, b1, c1}; }
/// A static triangle (0,0,0) (1,0,0) (0,1,0) against a point moving from p0 to p1.
std::array<Vec3, 8> vf_static(Vec3 p0, Vec3 p1) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  return vf(p0, a, b, c, p1, a, b, c);
}
/// Static edges.
std::array<Vec3, 8> ee_static(Vec3 a0, Vec3 a1, Vec3 b0, Vec3 b1) { return {a0, a1, b0, b1, a0, a1, b0, b1}; }

const double kUlpBelowTenth = std::nextafter(0.1, 0.0);

std::vector<NamedCase> degenerate_cases() {
  std::vector<NamedCase> cases;
  auto add = [&](std::string name, PairKind kind, std::array<Vec3, 8> rows, double thickness, bool collides,
                 std::optional<double> toi = std::nullopt) {
    cases.push_back({std::move(name), kind, rows, thickness, collides, toi});
  };
  const auto VF = PairKind::vertex_face;
  const auto EE = PairKind::edge_edge;
  for (double delta : {0.0, 0.01}) {
    const std::string d = delta == 0 ? " (δ=0)" : " (δ=0.01)";
    add("crossing the face interior" + d, VF, vf_static({0.25, 0.25, 1}, {0.25, 0.25, -1}), delta, true,
        delta == 0 ? std::optional(0.5) : std::nullopt);
    add("touching exactly at t=0, then leaving" + d, VF, vf_static({0.25, 0.25, 0}, {0.25, 0.25, 1}), delta, true, 0.0);
    add("touching exactly at t=1" + d, VF, vf_static({0.25, 0.25, 1}, {0.25, 0.25, 0}), delta, true, delta == 0 ? std::optional(1.0) : std::nullopt);
    add("vertex passing exactly through a face edge" + d, VF, vf_static({0.5, -1, 1}, {0.5, 1, -1}), delta, true,
        delta == 0 ? std::optional(0.5) : std::nullopt);
    add("vertex passing through a corner" + d, VF, vf_static({-1, -1, 1}, {1, 1, -1}), delta, true);
    add("coplanar motion into the face" + d, VF, vf_static({-1, 0.25, 0}, {0.25, 0.25, 0}), delta, true);
    add("coplanar motion beside the face" + d, VF, vf_static({2, -1, 0}, {2, 1, 0}), delta, false);
    add("zero motion, apart" + d, VF, vf_static({0.25, 0.25, 0.5}, {0.25, 0.25, 0.5}), delta, false);
    add("zero motion, touching" + d, VF, vf_static({0.25, 0.25, 0}, {0.25, 0.25, 0}), delta, true, 0.0);
    // c sweeps across the line ab: the face is a segment at t = 1/2; the point is far above it.
    add("hourglass face against a far point" + d, VF,
        vf({0.5, 0, 10}, {0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0, 10}, {0, 0, 0}, {1, 0, 0}, {0.5, -1, 0}), delta, false);
    // n(t) = (-t, t², 1) and p fixed: n·(p-a) = (t - 1/2)²/2 touches 0 at t = 1/2 without crossing it, with p's
    // projection inside the face there.
    add("double root: tangential contact at t=1/2" + d, VF,
        vf({0.5, 0.5, 0.125}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0.125}, {0, 0, 0}, {1, 0, 1}, {1, 1, 0}), delta, true,
        delta == 0 ? std::optional(0.5) : std::nullopt);
    add("edges crossing at t=1/2" + d, EE,
        {Vec3(-1, 0, 1), Vec3(1, 0, 1), Vec3(0, -1, 0), Vec3(0, 1, 0), Vec3(-1, 0, -1), Vec3(1, 0, -1), Vec3(0, -1, 0), Vec3(0, 1, 0)}, delta, true,
        delta == 0 ? std::optional(0.5) : std::nullopt);
    add("parallel edges 1 apart" + d, EE, ee_static({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}), delta, false);
    add("collinear overlapping edges" + d, EE, ee_static({0, 0, 0}, {2, 0, 0}, {1, 0, 0}, {3, 0, 0}), delta, true, 0.0);
    add("collinear edges with a gap" + d, EE, ee_static({0, 0, 0}, {1, 0, 0}, {1.5, 0, 0}, {3, 0, 0}), delta, false);
    add("endpoint touching the other edge's interior" + d, EE, ee_static({0, 0, 0}, {2, 0, 0}, {1, 0, 0}, {1, 1, 1}), delta, true);
    add("coplanar edges sweeping into each other" + d, EE,
        {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, 2, 0), Vec3(1, 3, 0), Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, -1, 0), Vec3(1, 1, 0)}, delta, true);
    add("zero-length edge on the other edge" + d, EE, ee_static({0, 0, 0}, {2, 0, 0}, {1, 0, 0}, {1, 0, 0}), delta, true);
    add("zero-area face, point on its segment" + d, VF,
        vf({0.5, 0, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0.5, 0, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}), delta, true);
  }
  add("parallel edges 1 apart, δ = 1", EE, ee_static({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}), 1.0, true);
  add("parallel edges 1 apart, δ one ulp below 1", EE, ee_static({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}), std::nextafter(1.0, 0.0), false);
  add("crossing edges at distance exactly δ", EE, ee_static({-1, 0, 0}, {1, 0, 0}, {0, -1, 0.1}, {0, 1, 0.1}), 0.1, true);
  add("crossing edges one ulp farther than δ", EE, ee_static({-1, 0, 0}, {1, 0, 0}, {0, -1, 0.1}, {0, 1, 0.1}), kUlpBelowTenth, false);
  add("point passing over the face at exactly δ", VF, vf_static({-1, 0.25, 0.1}, {2, 0.25, 0.1}), 0.1, true);
  add("point passing over the face one ulp farther than δ", VF, vf_static({-1, 0.25, 0.1}, {2, 0.25, 0.1}), kUlpBelowTenth, false);
  add("point passing a corner at exactly δ", VF, vf_static({-1, -0.1, -1}, {1, -0.1, 1}), 0.1, true);
  add("near miss at 1e-12 relative", VF, vf_static({0.25, 0.25, 1}, {0.25, 0.25, 1e-12}), 0.0, false);
  add("double root lifted by 2^-30 misses at δ=0", VF,
      vf({0.5, 0.5, 0.125 + std::ldexp(1.0, -30)}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0.125 + std::ldexp(1.0, -30)}, {0, 0, 0}, {1, 0, 1},
         {1, 1, 0}),
      0.0, false);
  add("double root lifted by 2^-30 hits at δ=2^-28", VF,
      vf({0.5, 0.5, 0.125 + std::ldexp(1.0, -30)}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0.125 + std::ldexp(1.0, -30)}, {0, 0, 0}, {1, 0, 1},
         {1, 1, 0}),
      std::ldexp(1.0, -28), true);
  return cases;
}

std::array<Vec3, 8> scaled(std::array<Vec3, 8> rows, double factor) {
  for (Vec3& row : rows) row *= factor;
  return rows;
}

void check_case(const std::string& name, PairKind kind, const std::array<Vec3, 8>& rows, double thickness, bool expected, std::optional<double> toi) {
  const std::string described =
      name + "\nrows (num,den per coordinate), δ = " + std::to_string(thickness) + ":\n" + testing::rational_rows(rows, expected ? 1 : 0);
  const Decision exact_only = decide(kind, rows, thickness, {false, true, 64});
  EXPECT_EQ(exact_only.collides, expected) << described;
  EXPECT_EQ(decide(kind, rows, thickness).collides, expected) << "filter + exact: " << described;
  const FilterVerdict verdict = filter_decide(kind, interval_rows(rows), Interval(thickness));
  if (verdict != FilterVerdict::inconclusive) {
    EXPECT_EQ(verdict == FilterVerdict::certainly_yes, expected) << "the filter contradicts the truth: " << described;
  }
  if (toi && exact_only.toi) {
    EXPECT_LE(exact_only.toi->lower, mpq_class(*toi)) << described;
    EXPECT_GE(exact_only.toi->upper, mpq_class(*toi)) << described;
    EXPECT_LE(mpq_class(exact_only.toi->upper - exact_only.toi->lower), mpq_class(1, mpz_class(1) << 60)) << described;
  }
}

TEST(DegenerateCases, EachHasItsKnownAnswerThreeWays) {
  for (const NamedCase& c : degenerate_cases()) check_case(c.name, c.kind, c.rows, c.thickness, c.collides, c.toi);
}

// Powers of two scale every coordinate exactly, so exact-touch cases must keep their answers; 2^±27 is about
// 1e∓8. Scaling by 1e∓8 itself rounds, so it is applied to the cases whose answer has a margin.
TEST(DegenerateCases, ScaledByOneE8AndOneEMinus8KeepTheirAnswers) {
  for (const NamedCase& c : degenerate_cases()) {
    for (double factor : {std::ldexp(1.0, -27), std::ldexp(1.0, 27)}) {
      check_case(c.name + " scaled by " + std::to_string(factor), c.kind, scaled(c.rows, factor), c.thickness * factor, c.collides, c.toi);
    }
  }
  const std::array<Vec3, 8> crossing = vf_static({0.25, 0.25, 1}, {0.25, 0.25, -1});
  const std::array<Vec3, 8> passing = vf_static({2, 0.25, 1}, {2, 0.25, -1});
  for (double factor : {1e-8, 1e8}) {
    check_case("crossing, scaled by " + std::to_string(factor), PairKind::vertex_face, scaled(crossing, factor), 0.0, true, std::nullopt);
    check_case("passing beside, scaled by " + std::to_string(factor), PairKind::vertex_face, scaled(passing, factor), 0.0, false, std::nullopt);
  }
}

}  // namespace
}  // namespace ccd::reference
