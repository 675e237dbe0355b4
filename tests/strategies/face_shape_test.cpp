// Face-shape pairs (core/shape.hpp): the strategies' cull and narrow phase (strategies/face_shape.hpp) against the
// reference's exact decision (reference/face_shape.hpp) on seeded random pairs at both δ and at every scale, and
// on the cases that decide the definition: a face through a box's corner or edge, a face inside a box at t = 0, a
// face cutting a box with no corner inside, a face grazing a sphere at exactly R + δ and one ulp farther.

#include "reference/face_shape.hpp"
#include "strategies/face_shape.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>

namespace ccd {
namespace {

const narrowphase::NarrowPhase& conservative() {
  static const auto narrow = narrowphase::make_narrow_phase("conservative");
  return *narrow;
}

/// The pair in hexadecimal floating point, which reads back exactly.
std::string describe(const Shape& shape, const FaceShapeRows& rows, double thickness) {
  std::ostringstream out;
  out << std::hexfloat;
  out << to_string(shape.kind) << " R=" << shape.radius << " h=" << shape.half_extents.transpose() << " δ=" << thickness
      << "\n c0=" << rows.centre_t0.transpose() << " c1=" << rows.centre_t1.transpose();
  for (int i = 0; i < 3; ++i) out << "\n f" << i << ": " << rows.face_t0[i].transpose() << " -> " << rows.face_t1[i].transpose();
  return out.str();
}

/// What the strategies answer: culled pairs do not collide, the rest go to the conservative narrow phase.
struct StrategyAnswer {
  bool culled = false;
  narrowphase::NarrowPhaseResult narrow;
  bool collides() const { return !culled && narrow.collides; }
};

/// use_gjk false: the certified axes decide every pair, so that a wrong certificate cannot hide behind GJK.
StrategyAnswer strategy_answer(const Shape& shape, const FaceShapeRows& rows, double thickness, bool use_gjk = true) {
  StrategyAnswer answer;
  answer.culled = strategies::cull_face_shape(shape, rows, thickness, use_gjk) == strategies::FaceShapeCull::certified_apart;
  if (!answer.culled) answer.narrow = strategies::narrow_phase_face_shape(conservative(), shape, rows, thickness);
  return answer;
}

/// Expects the strategies to find the pair when the reference says it collides (with a TOI no later than the
/// exact one), and never to cull a colliding pair, with libccd's GJK and with the certified axes alone. Returns
/// the reference's answer.
bool expect_no_miss(const Shape& shape, const FaceShapeRows& rows, double thickness) {
  const reference::Decision truth = reference::decide_face_shape(shape, rows, thickness, {true, true, 64});
  for (const bool use_gjk : {true, false}) {
    const StrategyAnswer answer = strategy_answer(shape, rows, thickness, use_gjk);
    if (!truth.collides) continue;
    EXPECT_FALSE(answer.culled) << "culled a colliding pair (GJK " << use_gjk << "): " << describe(shape, rows, thickness);
    EXPECT_TRUE(answer.collides()) << "missed: " << describe(shape, rows, thickness);
    if (answer.collides()) {
      EXPECT_LE(answer.narrow.toi, *truth.toi_floor) << "late TOI: " << describe(shape, rows, thickness);
    }
  }
  return truth.collides;
}

FaceShapeRows static_rows(const std::array<Vec3, 3>& face, const Vec3& centre) { return {face, face, centre, centre}; }

Shape sphere(double radius) { return {ShapeKind::sphere, radius, Vec3::Zero()}; }
Shape box(const Vec3& half) { return {ShapeKind::box, 0.0, half}; }

// Seeded random faces near each shape's surface, moving up to about a shape's size, at δ = 0 and δ = 1% of the
// size, scaled exactly by powers of two from 2^-900 to 2^900: no colliding pair is culled or missed, its TOI is
// never late, and the cull does cull (each kind of answer occurs, or the test would prove nothing). Every part draws
// the same pairs and checks its own (testing::Part).
class FaceShapeParts : public ::testing::TestWithParam<testing::Part> {};

TEST_P(FaceShapeParts, StrategiesMissNoRandomPairAtEitherThicknessAndEveryScale) {
  const std::uint64_t seed = 20261123;
  std::cout << "seed " << seed << "\n";
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), size(0.3, 1.0);
  for (const ShapeKind kind : {ShapeKind::sphere, ShapeKind::box}) {
    for (const int exponent : {-900, -40, 0, 40, 900}) {
      std::size_t colliding = 0, apart = 0, culled = 0, certified = 0;
      // At 2^±900 the reference's interval filter underflows or overflows and every decision is exact (slow): fewer
      // pairs there, still 8 to a part, enough for each kind of answer to occur in every part.
      const int pairs = std::abs(exponent) > 100 ? 32 : 60;
      std::size_t checked = 0;
      for (int n = 0; n < pairs; ++n) {
        const double s = std::ldexp(1.0, exponent);
        Shape shape = kind == ShapeKind::sphere ? sphere(size(random) * s) : box(Vec3(size(random), size(random), size(random)) * s);
        const Vec3 c0 = Vec3(unit(random), unit(random), unit(random)) * 0.2 * s;
        const Vec3 c1 = c0 + Vec3(unit(random), unit(random), unit(random)) * 0.3 * s;
        // A face around a point at 0.6 to 1.6 times the size from the centre, edges up to 0.5 long.
        const Vec3 direction = Vec3(unit(random), unit(random), unit(random)).normalized();
        const Vec3 anchor = c0 + direction * (1.0 + 0.5 * unit(random)) * s;
        FaceShapeRows rows;
        rows.centre_t0 = c0;
        rows.centre_t1 = c1;
        const Vec3 motion = Vec3(unit(random), unit(random), unit(random)) * 0.5 * s;
        for (int i = 0; i < 3; ++i) {
          rows.face_t0[i] = anchor + Vec3(unit(random), unit(random), unit(random)) * 0.25 * s;
          rows.face_t1[i] = rows.face_t0[i] + motion + Vec3(unit(random), unit(random), unit(random)) * 0.05 * s;
        }
        if (!GetParam().holds(static_cast<std::size_t>(n))) continue;
        ++checked;
        for (const double thickness : {0.0, 0.01 * s}) {
          SCOPED_TRACE(std::string(to_string(kind)) + " at 2^" + std::to_string(exponent) + ", pair " + std::to_string(n));
          const bool collides = expect_no_miss(shape, rows, thickness);
          (collides ? colliding : apart) += 1;
          culled += strategy_answer(shape, rows, thickness).culled ? 1 : 0;
          certified += strategy_answer(shape, rows, thickness, false).culled ? 1 : 0;
        }
      }
      std::cout << to_string(kind) << " 2^" << exponent << ": " << colliding << " colliding, " << apart << " apart, " << culled << " culled ("
                << certified << " by the certified axes alone)\n";
      const std::size_t decisions = 2 * checked;
      const std::size_t some = std::max<std::size_t>(1, decisions / 20);
      EXPECT_GE(colliding, 2 * some) << to_string(kind) << " at 2^" << exponent;
      EXPECT_GE(apart, 2 * some) << to_string(kind) << " at 2^" << exponent;
      EXPECT_GE(culled, some) << to_string(kind) << " at 2^" << exponent << ": the cull hardly culled";
      EXPECT_GE(certified, some) << to_string(kind) << " at 2^" << exponent << ": the axes hardly certified";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(RandomPairs, FaceShapeParts, ::testing::ValuesIn(testing::parts(4)), testing::part_name);

// A unit box at the origin and a small face moving through the region of its corner (1, 1, 1) along the diagonal,
// in the plane x + y + z = s, which touches the box only at that corner when s = 3.
TEST(FaceShape, AFaceThroughABoxCornerCollidesAndOneStoppingShortDoesNot) {
  const Shape cube = box(Vec3(1, 1, 1));
  auto plane_face = [](double s) {
    const double third = s / 3;
    return std::array<Vec3, 3>{Vec3(third + 0.2, third - 0.1, third - 0.1), Vec3(third - 0.1, third + 0.2, third - 0.1),
                               Vec3(third - 0.1, third - 0.1, third + 0.2)};
  };
  FaceShapeRows through{plane_face(3.3), plane_face(2.7), Vec3::Zero(), Vec3::Zero()};
  EXPECT_TRUE(expect_no_miss(cube, through, 0.0));
  FaceShapeRows short_of{plane_face(3.3), plane_face(3.15), Vec3::Zero(), Vec3::Zero()};
  EXPECT_FALSE(expect_no_miss(cube, short_of, 0.0));
  // It comes within 0.15/√3 ≈ 0.0866 of the corner.
  EXPECT_TRUE(expect_no_miss(cube, short_of, 0.09));
  EXPECT_FALSE(expect_no_miss(cube, short_of, 0.08));
  EXPECT_TRUE(strategy_answer(cube, through, 0.0).collides());
}

// A face moving across the box's edge x = y = 1 (along z) in the plane x + y = s, which touches that edge at s = 2.
TEST(FaceShape, AFaceAcrossABoxEdgeCollides) {
  const Shape cube = box(Vec3(1, 1, 1));
  auto plane_face = [](double s) {
    const double half = s / 2;
    return std::array<Vec3, 3>{Vec3(half + 0.3, half - 0.3, -0.5), Vec3(half - 0.3, half + 0.3, -0.5), Vec3(half, half, 0.5)};
  };
  EXPECT_TRUE(expect_no_miss(cube, {plane_face(2.4), plane_face(1.9), Vec3::Zero(), Vec3::Zero()}, 0.0));
  EXPECT_FALSE(expect_no_miss(cube, {plane_face(2.4), plane_face(2.1), Vec3::Zero(), Vec3::Zero()}, 0.0));
  // The box moves instead of the face: the same relative motion.
  EXPECT_TRUE(expect_no_miss(cube, {plane_face(2.4), plane_face(2.4), Vec3::Zero(), Vec3(0.25, 0.25, 0)}, 0.0));
  // A face in the plane z = 0 whose leading edge (on x + y = s) crosses the box's edge x = y = 1 at (1, 1, 0),
  // every corner of either far from the other: only the edge-edge pairs find it.
  auto edge_first = [](double s) {
    const double half = s / 2;
    return std::array<Vec3, 3>{Vec3(half + 2, half - 2, 0), Vec3(half - 2, half + 2, 0), Vec3(half + 3, half + 3, 0)};
  };
  EXPECT_TRUE(expect_no_miss(cube, {edge_first(2.4), edge_first(1.9), Vec3::Zero(), Vec3::Zero()}, 0.0));
  EXPECT_FALSE(expect_no_miss(cube, {edge_first(2.4), edge_first(2.1), Vec3::Zero(), Vec3::Zero()}, 0.0));
}

// A small face inside the box at t = 0, far from every side during the step, collides (the box is solid) at
// t = 0; so does a large face cutting through the box with every corner outside; a face beside the box does not.
TEST(FaceShape, AFaceInsideOrCuttingABoxAtTheStartCollidesAtTimeZero) {
  const Shape cube = box(Vec3(1, 1, 1));
  const std::array<Vec3, 3> inside{Vec3(-0.1, -0.1, 0), Vec3(0.1, -0.1, 0), Vec3(0, 0.1, 0)};
  const FaceShapeRows rows = static_rows(inside, Vec3::Zero());
  const reference::Decision truth = reference::decide_face_shape(cube, rows, 0.0, {true, true, 64});
  EXPECT_TRUE(truth.collides);
  EXPECT_EQ(*truth.toi_floor, 0.0);
  const StrategyAnswer answer = strategy_answer(cube, rows, 0.0);
  EXPECT_TRUE(answer.collides());
  EXPECT_EQ(answer.narrow.toi, 0.0);

  const std::array<Vec3, 3> cutting{Vec3(-10, -10, 0.5), Vec3(10, -10, 0.5), Vec3(0, 10, 0.5)};
  EXPECT_TRUE(expect_no_miss(cube, static_rows(cutting, Vec3::Zero()), 0.0));
  const std::array<Vec3, 3> beside{Vec3(-10, -10, 1.5), Vec3(10, -10, 1.5), Vec3(0, 10, 1.5)};
  EXPECT_FALSE(expect_no_miss(cube, static_rows(beside, Vec3::Zero()), 0.0));
  EXPECT_FALSE(expect_no_miss(cube, static_rows(beside, Vec3::Zero()), 0.25));
  EXPECT_TRUE(expect_no_miss(cube, static_rows(beside, Vec3::Zero()), 0.5));
}

// A static face in the plane z = d above a sphere's centre: it collides when d <= R + δ exactly. d is the largest
// double not above R + δ (the graze), then the next double (one ulp farther). 0.1 + 0.2 is not a double; 1 + 0.25
// is. The strategies find the graze; the reference says the ulp-farther face does not collide.
TEST(FaceShape, AFaceGrazingASphereAtExactlyRPlusDeltaCollidesAndOneUlpFartherDoesNot) {
  for (const auto& [radius, thickness] : {std::pair{0.1, 0.2}, std::pair{1.0, 0.25}, std::pair{1.0, 0x1p-54}, std::pair{0x1p-600, 0x1p-660}}) {
    SCOPED_TRACE("R = " + std::to_string(radius) + ", δ = " + std::to_string(thickness));
    const mpq_class exact = mpq_class(radius) + mpq_class(thickness);
    double graze = radius + thickness;
    if (mpq_class(graze) > exact) graze = std::nextafter(graze, 0.0);
    const double farther = std::nextafter(graze, std::numeric_limits<double>::infinity());
    ASSERT_GT(mpq_class(farther), exact);
    const double w = 4 * radius;
    for (const double d : {graze, farther}) {
      const std::array<Vec3, 3> face{Vec3(-w, -w, d), Vec3(w, -w, d), Vec3(0, w, d)};
      const bool collides = expect_no_miss(sphere(radius), static_rows(face, Vec3::Zero()), thickness);
      EXPECT_EQ(collides, d == graze);
    }
    EXPECT_GE(mpq_class(strategies::radius_plus_thickness(radius, thickness)), exact);
  }
}

// Degenerate and tiny faces: their normals and edge crosses are tiny or zero axes, whose norm underflows unless the
// axis is rescaled first (a face with edges of 2^-449 at distance 0.25 from a box, δ = 0.3, was once certified
// apart). Collinear faces and faces shrunk to a point, against both shapes.
TEST(FaceShape, DegenerateAndTinyFacesAreNeverCulledWhenTheyCollide) {
  const Shape cube = box(Vec3(0.25, 0.25, 0.25));
  const std::array<Vec3, 3> tiny{Vec3(0.5, 0, 0), Vec3(0.5, 0x1p-449, 0), Vec3(0.5, 0, 0x1p-450)};
  const std::array<Vec3, 3> collinear{Vec3(0.5, -1, 0), Vec3(0.5, 0, 0), Vec3(0.5, 1, 0)};
  const std::array<Vec3, 3> point{Vec3(0.5, 0, 0), Vec3(0.5, 0, 0), Vec3(0.5, 0, 0)};
  for (const auto& face : {tiny, collinear, point}) {
    for (const Shape& shape : {cube, sphere(0.25)}) {
      EXPECT_TRUE(expect_no_miss(shape, static_rows(face, Vec3::Zero()), 0.3));
      EXPECT_TRUE(expect_no_miss(shape, static_rows(face, Vec3::Zero()), 0.25));
      EXPECT_FALSE(expect_no_miss(shape, static_rows(face, Vec3::Zero()), 0.2));
    }
  }
  // A collinear face moving through the box, and a point face entering it.
  EXPECT_TRUE(expect_no_miss(cube, {collinear, {Vec3(0, -1, 0), Vec3(0, 0, 0), Vec3(0, 1, 0)}, Vec3::Zero(), Vec3::Zero()}, 0.0));
  EXPECT_TRUE(expect_no_miss(cube, {point, {Vec3(0.1, 0, 0), Vec3(0.1, 0, 0), Vec3(0.1, 0, 0)}, Vec3::Zero(), Vec3::Zero()}, 0.0));
}

/// The reference's exact decision as a narrow phase: with it, the face-shape wrapper's own margins are all that
/// stands between a rounded box and a miss.
class ExactNarrowPhase : public narrowphase::NarrowPhase {
 public:
  std::string name() const override { return "exact"; }
  bool conservative() const override { return true; }
  narrowphase::NarrowPhaseResult vertex_face(const narrowphase::PairRows& rows, double thickness) const override {
    return decide(reference::PairKind::vertex_face, rows, thickness);
  }
  narrowphase::NarrowPhaseResult edge_edge(const narrowphase::PairRows& rows, double thickness) const override {
    return decide(reference::PairKind::edge_edge, rows, thickness);
  }

 private:
  static narrowphase::NarrowPhaseResult decide(reference::PairKind kind, const narrowphase::PairRows& rows, double thickness) {
    const reference::Decision decision = reference::decide(kind, rows, thickness, {true, true, 64});
    narrowphase::NarrowPhaseResult result;
    result.collides = decision.collides;
    if (decision.collides) result.toi = *decision.toi_floor;
    return result;
  }
};

// The box's corners rounded: centre x = 1 and h.x = 2^-53 put the +x side at 1 + 2^-53, which rounds to 1. A face
// parallel to that side moves in from x = 1.5 to x = 1 + 2^-52, exactly δ = 2^-53 from the true side at t = 1 and
// 2δ from the rounded one. With an exact narrow phase only δ grown by the corners' rounding finds it (the
// conservative narrow phase's own error budget covers such a gap as well).
TEST(FaceShape, ABoxWhoseCornersRoundIsStillNotMissed) {
  const Shape thin = box(Vec3(0x1p-53, 1, 1));
  const double delta = 0x1p-53;
  auto at = [](double x) { return std::array<Vec3, 3>{Vec3(x, -0.5, -0.5), Vec3(x, 0.5, -0.5), Vec3(x, 0, 0.5)}; };
  const Vec3 centre(1, 0, 0);
  ASSERT_EQ(box_corners(centre, thin.half_extents)[1].x(), 1.0) << "the corner no longer rounds";
  const FaceShapeRows touching{at(1.5), at(1 + 0x1p-52), centre, centre};
  EXPECT_TRUE(expect_no_miss(thin, touching, delta));
  EXPECT_TRUE(strategies::narrow_phase_face_shape(ExactNarrowPhase(), thin, touching, delta).collides);
  EXPECT_FALSE(expect_no_miss(thin, {at(1.5), at(1 + 0x1p-51), centre, centre}, delta));
}

}  // namespace
}  // namespace ccd
