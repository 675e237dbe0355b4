// The self traversal (per-face queries with ordered output) against every pair of leaf boxes and against the
// tree-against-tree design it replaced: the same sorted list, for trees of 1, 2 and many faces, for a tree over
// faces that do not start at 0 (the second object of a scene), and after leaves were enlarged (apccd's dangling
// triangles), which changes boxes but not the tree.

#include "strategies/bvh/bvh.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <iostream>
#include <random>
#include <vector>

namespace ccd::bvh {
namespace {

struct Soup {
  MeshTopology topology;
  std::vector<Vec3> x0, x1;
};

/// `faces` small random triangles in a unit cube (dense enough that most faces overlap a few others), each with
/// its own three corners, moving by up to 0.017 over the step.
Soup random_soup(std::mt19937_64& random, std::size_t faces) {
  std::uniform_real_distribution<double> unit(0.0, 1.0), small(-0.05, 0.05), motion(-0.01, 0.01);
  Soup soup;
  std::vector<Face> list;
  for (std::size_t f = 0; f < faces; ++f) {
    const Vec3 centre(unit(random), unit(random), unit(random));
    for (int k = 0; k < 3; ++k) {
      const Vec3 corner = centre + Vec3(small(random), small(random), small(random));
      soup.x0.push_back(corner);
      soup.x1.push_back(corner + Vec3(motion(random), motion(random), motion(random)));
    }
    const auto first = static_cast<VertexId>(3 * f);
    list.push_back({first, first + 1, first + 2});
  }
  soup.topology = MeshTopology(soup.x0.size(), std::move(list));
  return soup;
}

/// Every pair (a < b) of the tree's faces whose leaf boxes intersect, sorted: the definition of the list.
std::vector<TrianglePair> every_leaf_pair(const TriangleBvh& tree) {
  std::vector<TrianglePair> pairs;
  const FaceId first = tree.first_face();
  const auto count = static_cast<FaceId>(tree.face_count());
  for (FaceId a = first; a < first + count; ++a) {
    for (FaceId b = a + 1; b < first + count; ++b) {
      const Box3& box_a = tree.nodes()[static_cast<std::size_t>(tree.leaf_of(a))].box;
      const Box3& box_b = tree.nodes()[static_cast<std::size_t>(tree.leaf_of(b))].box;
      if (box_a.intersects(box_b)) pairs.emplace_back(a, b);
    }
  }
  return pairs;
}

TEST(SelfOverlaps, EqualsEveryOverlappingLeafPairAndTheTreePairDesign) {
  const std::uint64_t seed = 20261123;
  std::cout << "seed " << seed << "\n";
  std::mt19937_64 random(seed);
  std::size_t overlapping = 0;
  for (const std::size_t faces : {1u, 2u, 3u, 17u, 2000u}) {
    const Soup soup = random_soup(random, faces);
    // The whole soup, and its second half as a tree of its own (first face > 0).
    for (const FaceId first : {FaceId{0}, static_cast<FaceId>(faces / 2)}) {
      const std::size_t count = faces - first;
      if (count == 0) continue;
      SCOPED_TRACE(std::to_string(faces) + " faces, tree from face " + std::to_string(first));
      TriangleBvh tree;
      tree.build(soup.topology, first, count, soup.x0);
      tree.refit(soup.topology, soup.x0, soup.x1, 0.001);
      auto expected = every_leaf_pair(tree);
      EXPECT_EQ(self_overlaps(tree), expected);
      EXPECT_EQ(self_overlaps_tree_pairs(tree), expected);
      overlapping += expected.size();
      // Enlarge a few leaves far beyond their faces (and their ancestors with them): new pairs appear.
      std::uniform_int_distribution<std::size_t> pick(0, count - 1);
      for (int k = 0; k < 3; ++k) {
        const FaceId f = first + static_cast<FaceId>(pick(random));
        const Box3& box = tree.nodes()[static_cast<std::size_t>(tree.leaf_of(f))].box;
        tree.enlarge_leaf(f, Box3(box.min() - Vec3::Constant(0.2), box.max() + Vec3::Constant(0.2)));
      }
      const auto enlarged = every_leaf_pair(tree);
      EXPECT_GE(enlarged.size(), expected.size());
      EXPECT_EQ(self_overlaps(tree), enlarged);
      EXPECT_EQ(self_overlaps_tree_pairs(tree), enlarged);
    }
  }
  EXPECT_GT(overlapping, 1000u) << "the soups must overlap for the comparison to mean anything";
}

}  // namespace
}  // namespace ccd::bvh
