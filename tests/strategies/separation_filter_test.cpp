// apccd's distance heuristic (strategies/separation_filter.hpp) may only ever say "apart" for pairs that do not
// come within δ: checked against the exact reference on the public data, the extremes suite and seeded random
// pairs; a single pair it wrongly calls apart fails, printed as a rational query.

#include "strategies/separation_filter.hpp"
#include "datasets/extremes_suite.hpp"
#include "datasets/query_file.hpp"
#include "reference/elementary_pair.hpp"
#include "tests/support/rational_rows.hpp"
#include "tests/support/scale_pairs.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <cfenv>
#include <cmath>
#include <iostream>
#include <random>

namespace ccd::strategies {
namespace {

/// Fails when the filter calls a colliding pair apart; returns whether it called the pair apart.
bool check(const narrowphase::PairRows& rows, bool vertex_face, double thickness, const std::string& where) {
  if (!provably_apart(rows, vertex_face, thickness)) return false;
  const auto kind = vertex_face ? reference::PairKind::vertex_face : reference::PairKind::edge_edge;
  const bool collides = reference::decide(kind, rows, thickness, {true, true, 64}).collides;
  EXPECT_FALSE(collides) << "called apart but collides: " << where << " at δ = " << thickness << ":\n" << testing::rational_rows(rows, 1);
  return true;
}

TEST(SeparationFilter, NeverCallsACollidingPairApartOnTheSharedData) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  std::size_t apart = 0, total = 0;
  for (const auto& path : datasets::discover_query_files({data / "sample-queries", data / "scalable-ccd-sample"})) {
    const datasets::QueryFile file = datasets::read_query_file(path);
    const bool vertex_face = file.kind == datasets::QueryKind::vertex_face;
    for (const datasets::Query& query : file.queries) {
      for (double thickness : {0.0, testing::small_thickness_for(query.rounded)}) {
        apart += check(query.rounded, vertex_face, thickness, path.string() + ":" + std::to_string(query.first_line)) ? 1 : 0;
        ++total;
      }
    }
  }
  std::cout << "called apart: " << apart << " of " << total << "\n";
  EXPECT_EQ(total, 2 * (testing::shared_query_count("sample-queries") + testing::shared_query_count("scalable-ccd-sample")))
      << "the data folder is missing queries";
}

// Only a pair the filter calls apart is checked against the reference: a filter that never said apart would pass
// without a single check, so the test also asks that it does say apart, on many of the suite's pairs.
TEST(SeparationFilter, NeverCallsACollidingPairApartOnTheExtremesSuite) {
  std::size_t apart = 0, total = 0;
  for (const datasets::ExtremeQuery& query : datasets::extremes_suite(1)) {
    for (double thickness : {0.0, query.positive_thickness}) {
      apart += check(query.rows, query.kind == datasets::QueryKind::vertex_face, thickness, query.family + ": " + query.name) ? 1 : 0;
      ++total;
    }
  }
  std::cout << "called apart (and checked): " << apart << " of " << total << "\n";
  EXPECT_GT(apart, total / 10);
}

// Exact rescaling changes no decision: the filter used to call colliding pairs apart at tiny scales (2^-530: a
// closest-point distance is an upper bound, and a·e - b² underflows) and pairs carried far during the step.
// Seven scales of each pair at both δ (a scale is skipped only where the pair or δ does not scale exactly). Returns
// how many scaled pairs were compared and how many pairs the filter calls apart at unit scale.
std::pair<std::size_t, std::size_t> expect_same_decision_at_every_scale(const std::vector<testing::ScalePair>& pairs) {
  std::size_t compared = 0, apart = 0;
  for (const testing::ScalePair& pair : pairs) {
    const bool vertex_face = pair.kind == datasets::QueryKind::vertex_face;
    for (double thickness : {0.0, pair.positive_thickness}) {
      const bool unit = provably_apart(pair.rows, vertex_face, thickness);
      apart += unit ? 1 : 0;
      for (int exponent : {-1000, -960, -530, -515, 500, 960, 1000}) {
        const auto scaled = datasets::scaled_exactly(pair.rows, exponent);
        const double scaled_thickness = std::ldexp(thickness, exponent);
        if (!scaled || (thickness > 0 && (!std::isnormal(scaled_thickness) || std::ldexp(scaled_thickness, -exponent) != thickness))) continue;
        // The first difference ends the comparison (one case to replay, not thousands of lines).
        if (provably_apart(*scaled, vertex_face, scaled_thickness) != unit) {
          ADD_FAILURE() << pair.where << " at 2^" << exponent << ", δ = " << thickness << ": apart at unit scale " << unit << ", not scaled";
          return {compared, apart};
        }
        ++compared;
      }
    }
  }
  return {compared, apart};
}

TEST(SeparationFilter, SameDecisionAtEveryExactScaleOnTheExtremesSuite) {
  const std::vector<testing::ScalePair> pairs = testing::extremes_scale_pairs();
  const auto [compared, apart] = expect_same_decision_at_every_scale(pairs);
  std::cout << "compared " << compared << " scaled pairs of " << pairs.size() * 2 * 7 << "; " << apart << " apart at unit scale\n";
  EXPECT_GT(compared, pairs.size() * 2 * 7 / 2);
  EXPECT_GT(apart, pairs.size() / 10) << "a filter that never says apart would pass: it must still separate";
}

TEST(SeparationFilter, SameDecisionAtEveryExactScaleOnThePublicData) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  const std::vector<testing::ScalePair> pairs = testing::public_data_scale_pairs(data);
  const auto [compared, apart] = expect_same_decision_at_every_scale(pairs);
  std::cout << "compared " << compared << " scaled pairs of " << pairs.size() * 2 * 7 << "; " << apart << " apart at unit scale\n";
  EXPECT_GT(compared, pairs.size() * 2 * 7 / 2);
  EXPECT_GT(apart, pairs.size() / 10) << "a filter that never says apart would pass: it must still separate";
}

TEST(SeparationFilter, DecisionsDoNotDependOnTheCallersRoundingMode) {
  const auto suite = datasets::extremes_suite(1);
  for (int mode : {FE_UPWARD, FE_DOWNWARD, FE_TOWARDZERO}) {
    for (const auto& query : suite) {
      const bool vertex_face = query.kind == datasets::QueryKind::vertex_face;
      const bool nearest = provably_apart(query.rows, vertex_face, query.positive_thickness);
      std::fesetround(mode);
      const bool other = provably_apart(query.rows, vertex_face, query.positive_thickness);
      std::fesetround(FE_TONEAREST);
      ASSERT_EQ(other, nearest) << query.family << ": " << query.name << ", mode " << mode;
    }
  }
}

TEST(SeparationFilter, NeverCallsACollidingPairApartOnRandomNearPairsAndCallsMostFarOnesApart) {
  const std::uint64_t seed = 20261121;
  std::cout << "seed " << seed << "\n";
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  std::size_t apart_near = 0, apart_far = 0;
  for (int i = 0; i < 3000; ++i) {
    const bool vertex_face = i % 2 == 0;
    narrowphase::PairRows rows;
    // Near: everything within a unit cube, small motions (many touch). Far: the second group shifted by 4.
    const bool far = i % 3 == 0;
    for (int k = 0; k < 4; ++k) {
      const bool second = vertex_face ? k > 0 : k > 1;
      rows[k] = Vec3(unit(random), unit(random), unit(random)) + (far && second ? Vec3(4, 0, 0) : Vec3::Zero());
      rows[k + 4] = rows[k] + 0.5 * Vec3(unit(random), unit(random), unit(random));
    }
    for (double thickness : {0.0, 0.05}) {
      const bool apart = check(rows, vertex_face, thickness, "random pair " + std::to_string(i));
      (far ? apart_far : apart_near) += apart ? 1 : 0;
    }
  }
  // Far pairs are 4 apart along x with motions of at most 0.5 per coordinate: every one of them must be called apart.
  EXPECT_EQ(apart_far, 2000u);
  std::cout << "near pairs called apart: " << apart_near << " of 4000\n";
}

}  // namespace
}  // namespace ccd::strategies
