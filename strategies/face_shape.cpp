#include "strategies/face_shape.hpp"

#include "strategies/bvh/bvh.hpp"
#include "strategies/narrowphase/round_to_nearest.hpp"

#include <ccd/ccd.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>

namespace ccd::strategies {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// How much GJK's grown shape exceeds δ, in the unit-scaled frame. GJK's own tolerances are absolute: it answers
/// "no" below |d|² < DBL_EPSILON (|d| < 1.5e-8) and within its iteration limit; 2^-20 (9.5e-7) keeps 60 times that
/// between the grown shape and anything within δ. It changes only how often a "no" reaches the certified check,
/// never what is culled: the check measures against δ itself.
constexpr double kGjkMargin = 0x1p-20;
constexpr unsigned long kGjkIterations = 100;

/// The slack a certified axis needs, per unit of A = Σ|a_k| of the axis a, in the unit-scaled frame where every
/// input is below 1 in magnitude and every relative corner below 2. The relative corners are rounded by at most
/// 2^-52 each (so a·q by 2^-52·A), each 3-term dot product by 3·2^-53·2·A < 2^-50·A, and the shape's extent
/// along a (R·|a| or Σ h_k |a_k|, plus δ·|a|, both at most 2·√3·max|a_k| <= 4A) by about 5 rounding units of
/// 4A, below 2^-48·A. Together under 2^-47·A; 2^-45·A leaves a factor 4 (round-to-nearest is set on entry).
/// The axis is rescaled first so that its largest |component| lies in [1/2, 1): A >= 1/2, so the absolute error
/// of a product that falls into the subnormal range (2^-1075) is nothing against the slack, and |a| >= 1/2 never
/// underflows.
constexpr double kAxisSlack = 0x1p-45;

/// The rounding of a box corner c ± h computed in doubles: at most half an ulp per coordinate, 2^-53·|corner|,
/// so √3·2^-53·M < 2^-52·M in distance for corners up to M in magnitude; kSubnormalRounding covers corners in
/// the subnormal range, where half an ulp is 2^-1075 absolute. Growing δ by this keeps the rounded box's answer
/// conservative for the exact one.
constexpr double kCornerRounding = 0x1p-52;
constexpr double kSubnormalRounding = 0x1p-1073;

/// One face-shape pair scaled exactly by 2^-exponent, the face taken relative to the centre at each end.
struct ScaledShapePair {
  std::array<Vec3, 6> relative;  // face corners minus centre, t = 0 then t = 1 (rounded, < 2 in magnitude)
  Shape shape;
  double thickness;  // δ·2^-exponent, rounded up
};

/// The pair rescaled so that its largest magnitude (coordinates, the shape's size and δ) lies in [1/2, 1);
/// nullopt when a value is not finite or when rescaling is not exact for some value (it would fall into the
/// subnormal range: pairs spanning about 2^1000 or more), where the callers do not cull.
std::optional<ScaledShapePair> scale(const Shape& shape, const FaceShapeRows& rows, double thickness) {
  double largest = std::abs(thickness);
  auto see = [&](double x) { largest = std::max(largest, std::abs(x)); };
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      see(rows.face_t0[i][k]);
      see(rows.face_t1[i][k]);
    }
  }
  for (int k = 0; k < 3; ++k) {
    see(rows.centre_t0[k]);
    see(rows.centre_t1[k]);
    see(shape.half_extents[k]);
  }
  see(shape.radius);
  if (!std::isfinite(largest) || largest == 0) return std::nullopt;
  const int exponent = std::ilogb(largest) + 1;
  bool exact = true;
  auto scaled = [&](double x) {
    const double y = std::ldexp(x, -exponent);
    exact = exact && std::ldexp(y, exponent) == x;
    return y;
  };
  auto scaled_point = [&](const Vec3& p) { return Vec3(scaled(p.x()), scaled(p.y()), scaled(p.z())); };
  ScaledShapePair pair;
  const Vec3 c0 = scaled_point(rows.centre_t0), c1 = scaled_point(rows.centre_t1);
  for (int i = 0; i < 3; ++i) {
    pair.relative[i] = scaled_point(rows.face_t0[i]) - c0;
    pair.relative[3 + i] = scaled_point(rows.face_t1[i]) - c1;
  }
  pair.shape = shape;
  pair.shape.radius = scaled(shape.radius);
  pair.shape.half_extents = scaled_point(shape.half_extents);
  // δ may round when scaled down into the subnormal range: up, then, and never refused.
  pair.thickness = std::ldexp(thickness, -exponent);
  if (std::ldexp(pair.thickness, exponent) < thickness) pair.thickness = std::nextafter(pair.thickness, kInfinity);
  if (!exact) return std::nullopt;
  return pair;
}

/// The shape's extent along a (its support value: R·|a| or Σ h_k |a_k|) plus δ·|a|, as computed.
double grown_extent(const Shape& shape, const Vec3& a, double thickness) {
  const double norm = a.norm();
  if (shape.kind == ShapeKind::sphere) return (shape.radius + thickness) * norm;
  return shape.half_extents.dot(a.cwiseAbs()) + thickness * norm;
}

/// Whether axis a certifies that every point of `points` (relative to the shape's centre) stays farther than δ
/// from the shape: all projections beyond the grown extent on one side, by more than the rounding budget. The axis
/// is first rescaled by a power of two so that its largest |component| lies in [1/2, 1): any vector is an axis,
/// and a tiny one would lose its norm to underflow (squares below 2^-1074) and with it the δ·|a| term.
bool certified_along(Vec3 a, std::span<const Vec3> points, const Shape& shape, double thickness) {
  const double largest = a.cwiseAbs().maxCoeff();
  if (!(largest > 0) || !std::isfinite(largest)) return false;
  const int exponent = std::ilogb(largest) + 1;
  for (int k = 0; k < 3; ++k) a[k] = std::ldexp(a[k], -exponent);
  const double sum = a.cwiseAbs().sum();
  double low = kInfinity, high = -kInfinity;
  for (const Vec3& q : points) {
    const double s = a.dot(q);
    low = std::min(low, s);
    high = std::max(high, s);
  }
  const double extent = grown_extent(shape, a, thickness);
  const double slack = kAxisSlack * sum;
  return low > extent + slack || high < -(extent + slack);
}

/// The point of triangle abc closest to the origin (Ericson, Real-Time Collision Detection §5.1.5), in doubles:
/// only a direction to try as an axis, so its rounding does not matter.
Vec3 closest_to_origin(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = -a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = -b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = -c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denominator = va + vb + vc;
  if (!(denominator != 0)) return (a + b + c) / 3;
  return a + ab * (vb / denominator) + ac * (vc / denominator);
}

/// Candidate separating axes for points (one or two triangles, relative to the centre) against the shape: the
/// directions to each triangle's closest point and to the centroid; for a box also its three axes, each
/// triangle's normal and each triangle edge crossed with each box axis (the axes of the triangle-box test).
bool certified_apart(std::span<const Vec3> points, const Shape& shape, double thickness) {
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& q : points) centroid += q;
  if (certified_along(centroid, points, shape, thickness)) return true;
  for (std::size_t t = 0; t + 2 < points.size(); t += 3) {
    const Vec3 &a = points[t], &b = points[t + 1], &c = points[t + 2];
    if (shape.kind == ShapeKind::sphere) {
      if (certified_along(closest_to_origin(a, b, c), points, shape, thickness)) return true;
      continue;
    }
    if (certified_along((b - a).cross(c - a), points, shape, thickness)) return true;
    for (int k = 0; k < 3; ++k) {
      const Vec3 axis = Vec3::Unit(k);
      if (t == 0 && certified_along(axis, points, shape, thickness)) return true;
      for (const Vec3& edge : {Vec3(b - a), Vec3(c - b), Vec3(a - c)}) {
        if (certified_along(axis.cross(edge), points, shape, thickness)) return true;
      }
    }
  }
  return false;
}

/// libccd objects: the hull of the relative corners, and the shape grown by `grow`, centred at the origin.
struct Hull {
  const std::array<Vec3, 6>* points;
};
struct Grown {
  const Shape* shape;
  double grow;
};

void hull_support(const void* object, const ccd_vec3_t* direction, ccd_vec3_t* out) {
  const Hull& hull = *static_cast<const Hull*>(object);
  const Vec3 d(direction->v[0], direction->v[1], direction->v[2]);
  const Vec3* best = &(*hull.points)[0];
  for (const Vec3& p : *hull.points) {
    if (p.dot(d) > best->dot(d)) best = &p;
  }
  for (int k = 0; k < 3; ++k) out->v[k] = (*best)[k];
}

void grown_support(const void* object, const ccd_vec3_t* direction, ccd_vec3_t* out) {
  const Grown& grown = *static_cast<const Grown*>(object);
  const Vec3 d(direction->v[0], direction->v[1], direction->v[2]);
  const double norm = d.norm();
  const Vec3 unit = norm > 0 ? Vec3(d / norm) : Vec3::Zero();
  Vec3 point = unit * grown.grow;
  if (grown.shape->kind == ShapeKind::sphere) {
    point += unit * grown.shape->radius;
  } else {
    for (int k = 0; k < 3; ++k) point[k] += d[k] >= 0 ? grown.shape->half_extents[k] : -grown.shape->half_extents[k];
  }
  for (int k = 0; k < 3; ++k) out->v[k] = point[k];
}

bool gjk_intersects(const ScaledShapePair& pair) {
  const Hull hull{&pair.relative};
  const Grown grown{&pair.shape, pair.thickness + kGjkMargin};
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = hull_support;
  ccd.support2 = grown_support;
  ccd.max_iterations = kGjkIterations;
  return ccdGJKIntersect(&hull, &grown, &ccd) != 0;
}

/// Keeps the earlier contact of two results of one pair.
void merge(narrowphase::NarrowPhaseResult& into, const narrowphase::NarrowPhaseResult& part) {
  into.hit_iteration_cap = into.hit_iteration_cap || part.hit_iteration_cap;
  into.achieved_tolerance = std::max(into.achieved_tolerance, part.achieved_tolerance);
  if (!part.collides) return;
  if (!into.collides || part.toi < into.toi || std::isnan(into.toi)) into.toi = part.toi;
  into.collides = true;
}

/// Whether the face at t = 0 may meet the solid box: no certified axis separates them at δ = 0.
bool may_meet_box_at_start(const Shape& shape, const FaceShapeRows& rows) {
  FaceShapeRows start = rows;
  start.face_t1 = rows.face_t0;
  start.centre_t1 = rows.centre_t0;
  const std::optional<ScaledShapePair> scaled = scale(shape, start, 0.0);
  if (!scaled) return true;
  return !certified_apart(std::span<const Vec3>(scaled->relative.data(), 3), scaled->shape, 0.0);
}

/// The centre's swept box widened by the shape's size (R, or h per axis) plus δ/2, with bvh::widened's rounding
/// room: a face whose δ/2-widened box misses it is farther than δ from the shape all step.
Box3 swept_shape_box(const Shape& shape, const Vec3& c0, const Vec3& c1, double thickness) {
  Box3 box;
  box.extend(c0);
  box.extend(c1);
  Vec3 widening;
  for (int k = 0; k < 3; ++k) widening[k] = (shape.kind == ShapeKind::sphere ? shape.radius : shape.half_extents[k]) + thickness / 2;
  return bvh::widened(box, widening);
}

}  // namespace

double radius_plus_thickness(double radius, double thickness) {
  const narrowphase::RoundToNearest nearest;
  const double sum = radius + thickness;
  if (!std::isfinite(sum)) return sum;
  // TwoSum (Knuth): sum + error == radius + thickness exactly.
  const double b_virtual = sum - radius;
  const double error = (radius - (sum - b_virtual)) + (thickness - b_virtual);
  return error > 0 ? std::nextafter(sum, kInfinity) : sum;
}

FaceShapeCull cull_face_shape(const Shape& shape, const FaceShapeRows& rows, double thickness, bool use_gjk) {
  const narrowphase::RoundToNearest nearest;
  const std::optional<ScaledShapePair> pair = scale(shape, rows, thickness);
  if (!pair) return FaceShapeCull::uncertified;
  if (use_gjk && gjk_intersects(*pair)) return FaceShapeCull::gjk_overlap;
  return certified_apart(pair->relative, pair->shape, pair->thickness) ? FaceShapeCull::certified_apart : FaceShapeCull::uncertified;
}

narrowphase::NarrowPhaseResult narrow_phase_face_shape(const narrowphase::NarrowPhase& narrow, const Shape& shape, const FaceShapeRows& rows,
                                                       double thickness, bool box_prefilter) {
  const narrowphase::RoundToNearest nearest;
  const auto& f0 = rows.face_t0;
  const auto& f1 = rows.face_t1;
  if (shape.kind == ShapeKind::sphere) {
    return narrow.vertex_face({rows.centre_t0, f0[0], f0[1], f0[2], rows.centre_t1, f1[0], f1[1], f1[2]},
                              radius_plus_thickness(shape.radius, thickness));
  }
  narrowphase::NarrowPhaseResult result;
  if (may_meet_box_at_start(shape, rows)) {
    result.collides = true;
    result.toi = 0.0;
    return result;
  }
  const std::array<Vec3, 8> c0 = box_corners(rows.centre_t0, shape.half_extents);
  const std::array<Vec3, 8> c1 = box_corners(rows.centre_t1, shape.half_extents);
  double largest = 0;
  for (int j = 0; j < 8; ++j) largest = std::max({largest, c0[j].cwiseAbs().maxCoeff(), c1[j].cwiseAbs().maxCoeff()});
  // The bound has room for its own rounding (√3/2 < 1); nextafter covers the rounding of the sum with δ.
  const double grown = std::nextafter(thickness + (kCornerRounding * largest + kSubnormalRounding), kInfinity);
  // Each elementary pair's two sides, swept over the step, in boxes widened by grown/2 with bvh::widened's rounding
  // room: boxes that miss hold primitives that stay farther than `grown` apart, which cannot collide.
  const double half = grown / 2;
  auto boxes_meet = [&](bool vertex_face, const narrowphase::PairRows& pair) {
    Box3 a, b;
    const int split = vertex_face ? 1 : 2;
    for (int i = 0; i < 4; ++i) {
      (i < split ? a : b).extend(pair[i]);
      (i < split ? a : b).extend(pair[i + 4]);
    }
    return bvh::widened(a, half).intersects(bvh::widened(b, half));
  };
  for_each_box_surface_pair(f0, f1, c0, c1, [&](bool vertex_face, const narrowphase::PairRows& pair) {
    if (box_prefilter && !boxes_meet(vertex_face, pair)) return false;
    merge(result, vertex_face ? narrow.vertex_face(pair, grown) : narrow.edge_edge(pair, grown));
    // The earliest TOI needs every part, unless one already touches at t = 0 (cloth resting on a box does).
    return result.collides && result.toi == 0.0;
  });
  return result;
}

void run_face_shape_stage(StepResult& result, const Scene& scene, const StepView& step, const narrowphase::NarrowPhase& narrow, bool audit) {
  if (scene.shape_objects().empty()) return;
  ScopedStageTimer timer(result.stages, "face-shape");
  struct Local {
    CollisionSet collisions;
    std::vector<FaceShapePair> tested;
    std::size_t boxes = 0, culled = 0, tests = 0;
  };
  tbb::enumerable_thread_specific<Local> locals;
  const double thickness = scene.thickness();
  for (const ObjectId s : scene.shape_objects()) {
    const SceneObject& shape_object = scene.object(s);
    const Shape& shape = *shape_object.shape;
    const VertexId centre = shape_object.first_vertex;
    const Box3 shape_box = swept_shape_box(shape, step.x0[centre], step.x1[centre], thickness);
    for (ObjectId o = 0; o < scene.objects().size(); ++o) {
      const SceneObject& object = scene.object(o);
      if (o == s || object.num_faces == 0 || !scene.may_collide(o, s)) continue;
      tbb::parallel_for(tbb::blocked_range<FaceId>(object.first_face, static_cast<FaceId>(object.first_face + object.num_faces), 256),
                        [&](const auto& range) {
                          Local& local = locals.local();
                          for (FaceId f = range.begin(); f != range.end(); ++f) {
                            if (!bvh::swept_face_box(scene.topology().face(f), step.x0, step.x1, thickness / 2).intersects(shape_box)) continue;
                            ++local.boxes;
                            const FaceShapePair pair{f, s};
                            const FaceShapeRows rows = face_shape_rows(scene, step.x0, step.x1, pair);
                            if (cull_face_shape(shape, rows, thickness, shape.kind == ShapeKind::box) == FaceShapeCull::certified_apart) {
                              ++local.culled;
                              continue;
                            }
                            ++local.tests;
                            if (audit) local.tested.push_back(pair);
                            const narrowphase::NarrowPhaseResult answer = narrow_phase_face_shape(narrow, shape, rows, thickness);
                            if (answer.collides) local.collisions.add(pair, answer.toi);
                          }
                        });
    }
  }
  std::size_t boxes = 0, culled = 0, tests = 0;
  std::vector<FaceShapePair> tested;
  for (Local& local : locals) {
    result.collisions.append(local.collisions);
    boxes += local.boxes;
    culled += local.culled;
    tests += local.tests;
    tested.insert(tested.end(), local.tested.begin(), local.tested.end());
  }
  result.collisions.normalize();
  result.counters.extra.emplace_back("face_shape_boxes", static_cast<double>(boxes));
  result.counters.extra.emplace_back("face_shape_culled", static_cast<double>(culled));
  result.counters.extra.emplace_back("face_shape_tests", static_cast<double>(tests));
  if (audit) {
    std::sort(tested.begin(), tested.end());
    if (!result.tested) result.tested.emplace();
    result.tested->face_shape = std::move(tested);
  }
}

}  // namespace ccd::strategies
