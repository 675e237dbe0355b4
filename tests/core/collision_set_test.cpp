#include "core/collision_set.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace ccd {
namespace {

TEST(PairId, EdgeEdgePairIsCanonicalInEitherOrder) {
  const Edge p = make_edge(7, 3), q = make_edge(1, 9);
  EXPECT_EQ(p, (Edge{3, 7}));
  EXPECT_EQ(make_edge_edge_pair(p, q), make_edge_edge_pair(q, p));
  EXPECT_EQ(make_edge_edge_pair(p, q).a, q);
}

TEST(CollisionSet, NormalizeSortsDeduplicatesAndKeepsEarliestToi) {
  CollisionSet set;
  set.add(VertexFacePair{5, 2}, 0.75);
  set.add(VertexFacePair{1, 9});
  set.add(VertexFacePair{5, 2});
  set.add(VertexFacePair{5, 2}, 0.25);
  set.add(make_edge_edge_pair(make_edge(0, 1), make_edge(2, 3)), 0.5);
  set.add(make_edge_edge_pair(make_edge(3, 2), make_edge(1, 0)));
  set.normalize();
  ASSERT_EQ(set.vertex_face().size(), 2u);
  EXPECT_EQ(set.vertex_face()[0].pair, (VertexFacePair{1, 9}));
  EXPECT_TRUE(std::isnan(set.vertex_face()[0].toi));
  EXPECT_EQ(set.vertex_face()[1].toi, 0.25);
  ASSERT_EQ(set.edge_edge().size(), 1u);
  EXPECT_EQ(set.edge_edge()[0].toi, 0.5);
  EXPECT_TRUE(set.contains(VertexFacePair{5, 2}));
  EXPECT_FALSE(set.contains(VertexFacePair{2, 5}));
}

// Threads normalize their own sets and merge them (strategies/elementary_tests.cpp): the result must be the set that
// one normalize of everything gives, pair for pair and TOI bit for TOI bit, duplicates across parts included.
TEST(CollisionSet, MergingNormalizedPartsGivesTheNormalizedWhole) {
  constexpr unsigned kSeed = 20261125;
  SCOPED_TRACE("seed " + std::to_string(kSeed));
  std::mt19937 random(kSeed);
  std::uniform_int_distribution<std::uint32_t> id(0, 40);
  std::uniform_int_distribution<int> kind(0, 3);
  std::uniform_real_distribution<double> time(0.0, 1.0);
  for (int parts : {1, 2, 3, 5, 16}) {
    CollisionSet whole;
    std::vector<CollisionSet> part(static_cast<std::size_t>(parts));
    for (int n = 0; n < 2000; ++n) {
      CollisionSet& into = part[static_cast<std::size_t>(n % parts)];
      // Few ids, so that a pair comes back often, in several parts, with and without a TOI.
      const double toi = kind(random) == 0 ? kNoToi : time(random);
      if (kind(random) < 2) {
        const VertexFacePair pair{id(random), id(random)};
        into.add(pair, toi);
        whole.add(pair, toi);
      } else {
        const EdgeEdgePair pair = make_edge_edge_pair(make_edge(id(random), id(random) + 41), make_edge(id(random), id(random) + 41));
        into.add(pair, toi);
        whole.add(pair, toi);
      }
    }
    whole.normalize();
    for (CollisionSet& p : part) p.normalize();
    for (std::size_t i = 1; i < part.size(); ++i) part[0].merge_normalized(part[i]);
    EXPECT_EQ(answers_digest(part[0]), answers_digest(whole)) << parts << " parts";
    EXPECT_EQ(part[0].size(), whole.size()) << parts << " parts";
    EXPECT_LT(whole.size(), 2000u) << "the draw must repeat pairs, or duplicates are not tested";
  }
}

TEST(CollisionSet, DifferenceGivesMissesAndFalseAlarms) {
  CollisionSet truth, reported;
  truth.add(VertexFacePair{1, 1});
  truth.add(VertexFacePair{2, 2});
  reported.add(VertexFacePair{2, 2});
  reported.add(VertexFacePair{3, 3});
  truth.normalize();
  reported.normalize();
  const CollisionSet missed = set_difference(truth, reported);
  const CollisionSet false_alarms = set_difference(reported, truth);
  ASSERT_EQ(missed.size(), 1u);
  EXPECT_EQ(missed.vertex_face()[0].pair, (VertexFacePair{1, 1}));
  ASSERT_EQ(false_alarms.size(), 1u);
  EXPECT_EQ(false_alarms.vertex_face()[0].pair, (VertexFacePair{3, 3}));
  EXPECT_FALSE(truth.same_pairs(reported));
  CollisionSet copy = truth;
  copy.append(truth);
  copy.normalize();
  EXPECT_TRUE(copy.same_pairs(truth));
}

// The digest in step records: equal answers give equal digests (whatever order they were added in); one TOI bit,
// one pair or a pair moved between the lists changes it.
TEST(CollisionSet, DigestSeesEveryPairAndEveryToiBit) {
  auto make = [](double toi, VertexId v) {
    CollisionSet set;
    set.add(EdgeEdgePair{{0, 1}, {2, 3}}, 0.5);
    set.add(VertexFacePair{v, 2}, toi);
    set.add(VertexFacePair{1, 1}, kNoToi);
    set.normalize();
    return answers_digest(set);
  };
  const std::string digest = make(0.25, 5);
  EXPECT_EQ(digest.size(), 16u);
  EXPECT_EQ(make(0.25, 5), digest);
  EXPECT_NE(make(std::nextafter(0.25, 1.0), 5), digest);
  EXPECT_NE(make(0.25, 6), digest);
  CollisionSet empty;
  EXPECT_NE(answers_digest(empty), digest);
  CollisionSet vertex_face, edge_edge;
  vertex_face.add(VertexFacePair{0, 1}, 0.5);
  edge_edge.add(EdgeEdgePair{{0, 1}, {0, 0}}, 0.5);
  EXPECT_NE(answers_digest(vertex_face), answers_digest(edge_edge));
}

// Face-shape pairs are a third list: normalized, compared and subtracted like the others, and in the digest only
// when there are any (a set without them keeps the digest it had before shapes existed: pinned here).
TEST(CollisionSet, FaceShapePairsAreAThirdListAndLeaveOtherDigestsAlone) {
  CollisionSet truth, reported;
  truth.add(FaceShapePair{4, 2}, 0.5);
  truth.add(FaceShapePair{3, 2}, 0.75);
  truth.add(FaceShapePair{3, 2}, 0.25);
  truth.add(VertexFacePair{0, 1}, 0.5);
  truth.normalize();
  ASSERT_EQ(truth.face_shape().size(), 2u);
  EXPECT_EQ(truth.face_shape()[0].pair, (FaceShapePair{3, 2}));
  EXPECT_EQ(truth.face_shape()[0].toi, 0.25);
  EXPECT_EQ(truth.size(), 3u);
  EXPECT_TRUE(truth.contains(FaceShapePair{4, 2}));
  EXPECT_FALSE(truth.contains(FaceShapePair{4, 1}));
  reported.add(FaceShapePair{3, 2});
  reported.add(VertexFacePair{0, 1});
  reported.normalize();
  const CollisionSet missed = set_difference(truth, reported);
  ASSERT_EQ(missed.size(), 1u);
  EXPECT_EQ(missed.face_shape()[0].pair, (FaceShapePair{4, 2}));
  EXPECT_FALSE(truth.same_pairs(reported));

  CollisionSet vertex_face;
  vertex_face.add(VertexFacePair{0, 1}, 0.5);
  vertex_face.normalize();
  // FNV-1a of the words 1, (0 << 32 | 1), bits(0.5), 0: what the digest gave before face-shape pairs existed.
  EXPECT_EQ(answers_digest(vertex_face), "c88267a2f0f70fc8");
  CollisionSet with_shape = vertex_face;
  with_shape.add(FaceShapePair{1, 0}, 0.5);
  with_shape.normalize();
  EXPECT_NE(answers_digest(with_shape), answers_digest(vertex_face));
}

}  // namespace
}  // namespace ccd
