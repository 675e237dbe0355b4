// boxes_overlap is Eigen's AlignedBox::intersects written out (core/vec.hpp): the same answer for every pair of boxes,
// the ones that sit on its edges and seeded random ones.

#include "core/vec.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <iostream>
#include <limits>
#include <random>
#include <vector>

namespace ccd {
namespace {

TEST(BoxesOverlap, AnswersAsEigensIntersectsOnEdgeCasesAndRandomBoxes) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double tiny = std::numeric_limits<double>::denorm_min();
  std::vector<Box3> boxes{
      Box3(),                                                     // empty (min > max)
      Box3(Vec3(0, 0, 0), Vec3(1, 1, 1)),                         // unit
      Box3(Vec3(1, 1, 1), Vec3(2, 2, 2)),                         // touching the unit box at a corner
      Box3(Vec3(1, 0, 0), Vec3(2, 1, 1)),                         // touching it along a face
      Box3(Vec3(std::nextafter(1.0, 2.0), 0, 0), Vec3(2, 1, 1)),  // one ulp off that face
      Box3(Vec3(0.5, 0.5, 0.5), Vec3(0.5, 0.5, 0.5)),             // a point inside
      Box3(Vec3(-0.0, -0.0, -0.0), Vec3(0.0, 0.0, 0.0)),          // signed zeros
      Box3(Vec3(tiny, tiny, tiny), Vec3(tiny, tiny, tiny)),       // the smallest subnormal
      Box3(Vec3(nan, 0, 0), Vec3(1, 1, 1)),                       // NaN corners
      Box3(Vec3(0, 0, 0), Vec3(1, nan, 1)),
      Box3(Vec3(-1e308, -1e308, -1e308), Vec3(1e308, 1e308, 1e308)),
  };
  const std::uint64_t seed = 20261126;
  std::cout << "seed " << seed << "\n";
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  for (int i = 0; i < 2000; ++i) {
    Box3 box(Vec3(coordinate(random), coordinate(random), coordinate(random)));
    box.extend(Vec3(coordinate(random), coordinate(random), coordinate(random)));
    boxes.push_back(box);
  }
  std::size_t overlapping = 0;
  for (const Box3& a : boxes) {
    for (const Box3& b : boxes) {
      ASSERT_EQ(boxes_overlap(a, b), a.intersects(b)) << "a = [" << a.min().transpose() << "] .. [" << a.max().transpose() << "], b = ["
                                                      << b.min().transpose() << "] .. [" << b.max().transpose() << "]";
      overlapping += boxes_overlap(a, b) ? 1 : 0;
    }
  }
  EXPECT_GT(overlapping, 0u);
  EXPECT_LT(overlapping, boxes.size() * boxes.size());
}

}  // namespace
}  // namespace ccd
