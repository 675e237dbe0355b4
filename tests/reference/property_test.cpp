// Seeded random pairs, near-degenerate ones included: the filter (and its separation pre-check alone) never
// changes an answer, answers are monotone in δ, and symmetries of the problem never change them (metamorphic tests).

#include "reference/certified_filter.hpp"
#include "reference/elementary_pair.hpp"
#include "tests/support/rational_rows.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <random>

namespace ccd::reference {
namespace {

constexpr std::uint64_t kSeed = 0x5eed2026;

struct RandomPair {
  PairKind kind;
  std::array<Vec3, 8> rows;
};

/// Three families, so degenerate configurations are common: coordinates on a coarse grid of eighths (coplanar,
/// collinear and touching configurations arise often), small perturbations of a touching configuration, and
/// general doubles.
std::vector<RandomPair> random_pairs(std::size_t count, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_int_distribution<int> grid(-8, 8);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-40, -10);
  std::vector<RandomPair> pairs;
  for (std::size_t i = 0; i < count; ++i) {
    RandomPair pair{i % 2 == 0 ? PairKind::vertex_face : PairKind::edge_edge, {}};
    const int family = static_cast<int>(i % 6) / 2;
    for (Vec3& row : pair.rows) {
      for (int k = 0; k < 3; ++k) {
        if (family == 0)
          row[k] = grid(random) / 8.0;
        else if (family == 1)
          row[k] = grid(random) / 4.0 + (random() % 3 == 0 ? std::ldexp(uniform(random), exponent(random)) : 0.0);
        else
          row[k] = uniform(random);
      }
    }
    if (family == 0 && random() % 2 == 0) {
      for (int k = 0; k < 4; ++k) pair.rows[k + 4] = pair.rows[k];  // zero motion
    }
    pairs.push_back(pair);
  }
  return pairs;
}

std::string describe(const RandomPair& pair, double thickness) {
  return std::string(pair.kind == PairKind::vertex_face ? "vertex-face" : "edge-edge") + ", δ = " + std::to_string(thickness) + ", seed " +
         std::to_string(kSeed) + ":\n" + testing::rational_rows(pair.rows);
}

// Tests of many random pairs come in parts (testing::Part): every part draws the same pairs and checks its own.
class ReferencePropertyParts : public ::testing::TestWithParam<testing::Part> {};

TEST_P(ReferencePropertyParts, FilterThenExactEqualsExactOnly) {
  std::cout << "seed " << kSeed << "\n";
  const std::vector<RandomPair> pairs = random_pairs(1500, kSeed);
  for (double thickness : {0.0, 0.05}) {
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      if (!GetParam().holds(i)) continue;
      const RandomPair& pair = pairs[i];
      const bool exact_only = decide(pair.kind, pair.rows, thickness, {false, false, 0}).collides;
      const bool filtered = decide(pair.kind, pair.rows, thickness).collides;
      ASSERT_EQ(filtered, exact_only) << describe(pair, thickness);
    }
  }
}

/// A random pair pulled apart: the second primitive is moved by a random offset whose length is drawn on a log
/// scale around δ, so that many pairs end just outside δ (where the separation pre-check must stop short) and many
/// just inside (where it must never answer).
std::vector<RandomPair> near_pairs(std::size_t count, std::uint64_t seed, double thickness) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::uniform_real_distribution<double> log_length(-3.0, 1.0);
  std::vector<RandomPair> pairs = random_pairs(count, seed);
  for (RandomPair& pair : pairs) {
    const Vec3 offset = Vec3(uniform(random), uniform(random), uniform(random)).normalized() * std::pow(10.0, log_length(random)) *
                        (thickness > 0 ? 20 * thickness : 1.0);
    const int split = pair.kind == PairKind::vertex_face ? 1 : 2;
    for (int k = split; k < 4; ++k) {
      pair.rows[k] += offset;
      pair.rows[k + 4] += offset;
    }
  }
  return pairs;
}

// The filter's separation pre-check alone, at every depth, never calls a colliding pair apart; and it does call
// most far pairs apart (otherwise it would prove nothing and this test could not fail).
TEST_P(ReferencePropertyParts, SeparationPreCheckNeverRulesOutACollision) {
  std::cout << "seed " << kSeed + 3 << "\n";
  for (double thickness : {0.0, 0.05}) {
    std::size_t apart = 0, colliding = 0, checked = 0;
    const std::vector<RandomPair> pairs = near_pairs(2000, kSeed + 3, thickness);
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      if (!GetParam().holds(i)) continue;
      ++checked;
      const RandomPair& pair = pairs[i];
      const bool collides = decide(pair.kind, pair.rows, thickness, {false, false, 0}).collides;
      colliding += collides;
      for (int depth : {0, 2, 5}) {
        const bool called_apart = certainly_apart(pair.kind, interval_rows(pair.rows), Interval(thickness), depth);
        ASSERT_FALSE(called_apart && collides) << "depth " << depth << ": " << describe(pair, thickness);
        apart += depth == 2 && called_apart;
      }
    }
    EXPECT_GT(apart, checked / 4) << "δ = " << thickness;
    // About 1 in 20 of these pairs collides (24 to 87 of each part's 500): a part with fewer than 1 in 40 would
    // hardly test the pre-check against colliding pairs at all.
    EXPECT_GT(colliding, checked / 40) << "δ = " << thickness;
    std::cout << "δ = " << thickness << ": " << apart << " of " << checked << " called apart at depth 2, " << colliding << " colliding\n";
  }
}

INSTANTIATE_TEST_SUITE_P(RandomPairs, ReferencePropertyParts, ::testing::ValuesIn(testing::parts(4)), testing::part_name);

// On its threshold: a vertex resting exactly δ above a face is within δ (it collides) and is not called apart;
// one ulp higher it is apart, and the pre-check proves it.
TEST(ReferenceProperty, SeparationPreCheckIsExactAtDistanceDelta) {
  const double thickness = 0.1;
  for (double height : {thickness, std::nextafter(thickness, 1.0)}) {
    std::array<Vec3, 8> rows = {Vec3(0.25, 0.25, height), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
    for (int k = 0; k < 4; ++k) rows[k + 4] = rows[k];
    const bool collides = decide(PairKind::vertex_face, rows, thickness, {false, false, 0}).collides;
    EXPECT_EQ(collides, height == thickness);
    EXPECT_EQ(certainly_apart(PairKind::vertex_face, interval_rows(rows), Interval(thickness), 2), !collides) << "height " << height;
  }
}

TEST(ReferenceProperty, MonotoneInThickness) {
  const double thicknesses[] = {0.0, 1.0 / 64, 1.0 / 16, 0.25};
  for (const RandomPair& pair : random_pairs(1500, kSeed + 1)) {
    bool previous = false;
    for (double thickness : thicknesses) {
      const bool collides = decide(pair.kind, pair.rows, thickness).collides;
      ASSERT_TRUE(collides || !previous) << "collides at a smaller δ but not at " << describe(pair, thickness);
      previous = collides;
    }
  }
}

/// Variants of a pair that describe the same geometric question.
std::vector<std::pair<std::string, RandomPair>> symmetric_variants(const RandomPair& pair, double& thickness_scale) {
  std::vector<std::pair<std::string, RandomPair>> variants;
  const auto& r = pair.rows;
  RandomPair reversed = pair;
  for (int k = 0; k < 4; ++k) std::swap(reversed.rows[k], reversed.rows[k + 4]);
  variants.emplace_back("time reversed", reversed);
  auto permuted = [&](std::array<int, 4> order) {
    RandomPair p = pair;
    for (int k = 0; k < 4; ++k) {
      p.rows[k] = r[order[k]];
      p.rows[k + 4] = r[order[k] + 4];
    }
    return p;
  };
  if (pair.kind == PairKind::vertex_face) {
    variants.emplace_back("face corners rotated", permuted({0, 2, 3, 1}));
    variants.emplace_back("face corners reflected", permuted({0, 1, 3, 2}));
  } else {
    variants.emplace_back("edge a endpoints swapped", permuted({1, 0, 2, 3}));
    variants.emplace_back("edge b endpoints swapped", permuted({0, 1, 3, 2}));
    variants.emplace_back("edges swapped", permuted({2, 3, 0, 1}));
  }
  thickness_scale = std::ldexp(1.0, -20);
  RandomPair scaled = pair;
  for (Vec3& row : scaled.rows) row *= thickness_scale;
  variants.emplace_back("scaled by 2^-20 (with δ)", scaled);
  return variants;
}

TEST(ReferenceProperty, SymmetriesNeverChangeTheAnswer) {
  for (double thickness : {0.0, 0.05}) {
    for (const RandomPair& pair : random_pairs(1200, kSeed + 2)) {
      const bool answer = decide(pair.kind, pair.rows, thickness).collides;
      double scale = 1.0;
      for (const auto& [name, variant] : symmetric_variants(pair, scale)) {
        const double variant_thickness = name.rfind("scaled", 0) == 0 ? thickness * scale : thickness;
        ASSERT_EQ(decide(variant.kind, variant.rows, variant_thickness).collides, answer)
            << name << " changed the answer of " << describe(pair, thickness);
      }
    }
  }
}

}  // namespace
}  // namespace ccd::reference

namespace ccd::reference {
namespace {

// The exact TOI's floor is the largest double not after the earliest contact: exactly 0.5 for a contact at 1/2,
// the double just below 1/3 for a contact at 1/3 (1/3 is not a double), and for an irrational time a double whose
// successor lies beyond the exact interval. A double TOI is late exactly when it exceeds the floor.
TEST(ReferenceToi, FloorIsTheLargestDoubleNotAfterTheEarliestContact) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  auto vertex_through = [&](double z0, double z1) { return std::array<Vec3, 8>{Vec3(0.25, 0.25, z0), a, b, c, Vec3(0.25, 0.25, z1), a, b, c}; };
  const DecisionRequest with_toi{true, true, 64};
  const Decision half = decide(PairKind::vertex_face, vertex_through(1, -1), 0.0, with_toi);
  ASSERT_TRUE(half.collides);
  EXPECT_EQ(*half.toi_floor, 0.5);
  const Decision third = decide(PairKind::vertex_face, vertex_through(1, -2), 0.0, with_toi);  // z = 1 - 3t: t = 1/3
  const double below_third = 1.0 / 3.0;  // round to nearest of 1/3 lies below it (binary 0.0101...01|0101...)
  ASSERT_LT(mpq_class(below_third), mpq_class(1, 3));
  EXPECT_EQ(*third.toi_floor, below_third);
  EXPECT_GT(mpq_class(std::nextafter(below_third, 1.0)), mpq_class(1, 3));
  // Within δ = 0.5 of the face: the vertex descends z = 2 - 2t and is within δ from t = 3/4.
  const Decision thick = decide(PairKind::vertex_face, vertex_through(2, 0), 0.5, with_toi);
  EXPECT_EQ(*thick.toi_floor, 0.75);
  // An irrational time: a vertex passing a slanted moving face (a quadratic coplanarity condition).
  std::mt19937_64 random(20261122);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::size_t checked = 0;
  for (int i = 0; i < 200; ++i) {
    std::array<Vec3, 8> rows;
    for (Vec3& row : rows) row = Vec3(unit(random), unit(random), unit(random));
    const Decision decision = decide(PairKind::edge_edge, rows, 0.05, with_toi);
    if (!decision.collides) continue;
    const double floor = *decision.toi_floor;
    EXPECT_LE(mpq_class(floor), decision.toi->upper);
    EXPECT_GE(mpq_class(std::nextafter(floor, 2.0)), decision.toi->lower) << "the floor must be the largest such double";
    ++checked;
  }
  EXPECT_GT(checked, 20u);
}

}  // namespace
}  // namespace ccd::reference
