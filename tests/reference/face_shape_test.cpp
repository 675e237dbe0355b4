// The reference's triangle-box test (reference/face_shape.hpp), the part of the face-shape decision that is not an
// elementary pair: against CGAL's own exact do_intersect(Triangle_3, Iso_cuboid_3) on seeded random triangles
// whose corners lie on a coarse grid, so that many touch the box exactly at a corner, an edge or a side.

#include "reference/face_shape.hpp"
#include "tests/support/test_support.hpp"

#include <CGAL/Intersections_3/Iso_cuboid_3_Triangle_3.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/gmpxx.h>
#include <gtest/gtest.h>

#include <iostream>
#include <random>

namespace ccd::reference {
namespace {

using Kernel = CGAL::Simple_cartesian<mpq_class>;

// Every part draws the same triangles and checks its own (testing::Part).
class TriangleMeetsBoxParts : public ::testing::TestWithParam<testing::Part> {};

TEST_P(TriangleMeetsBoxParts, AgreesWithCgalOnGridTrianglesThatOftenTouch) {
  const std::uint64_t seed = 20261123;
  std::cout << "seed " << seed << "\n";
  std::mt19937_64 random(seed);
  std::uniform_int_distribution<int> coordinate(-8, 8), centre(-4, 4), half(1, 4);
  auto grid = [&](int steps) { return mpq_class(steps, 4); };  // multiples of 1/4
  std::size_t meets = 0, apart = 0, checked = 0;
  const int triangles = 3000;
  for (int n = 0; n < triangles; ++n) {
    const RationalPoint c{grid(centre(random)), grid(centre(random)), grid(centre(random))};
    const RationalPoint h{grid(half(random)), grid(half(random)), grid(half(random))};
    std::array<RationalPoint, 3> triangle;
    for (auto& corner : triangle) corner = {grid(coordinate(random)), grid(coordinate(random)), grid(coordinate(random))};
    const Kernel::Triangle_3 cgal_triangle(Kernel::Point_3(triangle[0][0], triangle[0][1], triangle[0][2]),
                                           Kernel::Point_3(triangle[1][0], triangle[1][1], triangle[1][2]),
                                           Kernel::Point_3(triangle[2][0], triangle[2][1], triangle[2][2]));
    if (cgal_triangle.is_degenerate() || !GetParam().holds(static_cast<std::size_t>(n))) continue;
    ++checked;
    const Kernel::Iso_cuboid_3 cgal_box(Kernel::Point_3(c[0] - h[0], c[1] - h[1], c[2] - h[2]),
                                        Kernel::Point_3(c[0] + h[0], c[1] + h[1], c[2] + h[2]));
    const bool expected = CGAL::do_intersect(cgal_triangle, cgal_box);
    EXPECT_EQ(triangle_meets_box(triangle, c, h), expected) << "triangle " << n;
    (expected ? meets : apart) += 1;
  }
  std::cout << meets << " meet the box, " << apart << " do not\n";
  EXPECT_GT(meets, checked / 10);
  EXPECT_GT(apart, checked / 10);
}

INSTANTIATE_TEST_SUITE_P(GridTriangles, TriangleMeetsBoxParts, ::testing::ValuesIn(testing::parts(4)), testing::part_name);

// Degenerate triangles (CGAL's test does not take them): a segment and a point, touching the box, inside it and
// outside it.
TEST(TriangleMeetsBox, SegmentsAndPointsMeetTheBoxWhereTheyTouchIt) {
  const RationalPoint c{0, 0, 0}, h{1, 1, 1};
  auto point = [](double x, double y, double z) { return RationalPoint{x, y, z}; };
  EXPECT_TRUE(triangle_meets_box({point(1, 1, 1), point(1, 1, 1), point(1, 1, 1)}, c, h));
  EXPECT_FALSE(triangle_meets_box({point(1, 1, 1.25), point(1, 1, 1.25), point(1, 1, 1.25)}, c, h));
  EXPECT_TRUE(triangle_meets_box({point(0, 0, 0), point(0, 0, 0), point(0, 0, 0)}, c, h));
  // A segment through the box with both ends outside, one touching the edge x = y = 1 at its midpoint, one
  // passing beside that edge.
  EXPECT_TRUE(triangle_meets_box({point(1.5, -0.5, 0), point(-0.5, 1.5, 0), point(0.5, 0.5, 0)}, c, h));
  EXPECT_TRUE(triangle_meets_box({point(2, 0, 0), point(0, 2, 0), point(1, 1, 0)}, c, h));
  EXPECT_FALSE(triangle_meets_box({point(2.25, 0, 0), point(0, 2.25, 0), point(1.125, 1.125, 0)}, c, h));
}

}  // namespace
}  // namespace ccd::reference
