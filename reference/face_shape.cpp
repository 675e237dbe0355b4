#include "reference/face_shape.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ccd::reference {
namespace {

RationalPoint rational(const Vec3& v) {
  if (!v.allFinite()) throw std::invalid_argument("reference: a coordinate is not finite");
  return {mpq_class(v.x()), mpq_class(v.y()), mpq_class(v.z())};  // exact: every double is a rational
}

RationalPoint minus(const RationalPoint& a, const RationalPoint& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

RationalPoint cross(const RationalPoint& a, const RationalPoint& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

mpq_class dot(const RationalPoint& a, const RationalPoint& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/// Folds one elementary decision into the face-shape decision: collides if any does, decided by the filter only
/// if all were, earliest TOI.
void merge(Decision& into, const Decision& part) {
  if (part.decided_by == DecidedBy::exact) into.decided_by = DecidedBy::exact;
  if (!part.collides) return;
  if (!into.collides) {
    into.collides = true;
    into.toi = part.toi;
    into.toi_floor = part.toi_floor;
    into.toi_ceiling = part.toi_ceiling;
    return;
  }
  // The earliest TOI lies in [min of lowers, min of uppers]: no wider than the narrowest part's interval.
  if (part.toi && into.toi) {
    if (part.toi->lower < into.toi->lower) into.toi->lower = part.toi->lower;
    if (part.toi->upper < into.toi->upper) into.toi->upper = part.toi->upper;
  } else if (part.toi) {
    into.toi = part.toi;
  }
  if (part.toi_floor && (!into.toi_floor || *part.toi_floor < *into.toi_floor)) into.toi_floor = part.toi_floor;
  // Both are monotone in t: the earliest time's ceiling is the least of the parts'.
  if (part.toi_ceiling && (!into.toi_ceiling || *part.toi_ceiling < *into.toi_ceiling)) into.toi_ceiling = part.toi_ceiling;
}

}  // namespace

bool triangle_meets_box(const std::array<RationalPoint, 3>& triangle, const RationalPoint& centre, const RationalPoint& half_extents) {
  const std::array<RationalPoint, 3> v{minus(triangle[0], centre), minus(triangle[1], centre), minus(triangle[2], centre)};
  // Along `axis` the triangle projects onto [min, max] and the box onto [-r, r], r = Σ h_k |axis_k|. A zero axis
  // projects everything onto 0 and separates nothing.
  auto separates = [&](const RationalPoint& axis) {
    const mpq_class p0 = dot(axis, v[0]), p1 = dot(axis, v[1]), p2 = dot(axis, v[2]);
    const mpq_class low = std::min({p0, p1, p2}), high = std::max({p0, p1, p2});
    const mpq_class r = half_extents[0] * abs(axis[0]) + half_extents[1] * abs(axis[1]) + half_extents[2] * abs(axis[2]);
    return low > r || high < -r;
  };
  const std::array<RationalPoint, 3> box_axes{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  for (const RationalPoint& axis : box_axes) {
    if (separates(axis)) return false;
  }
  const std::array<RationalPoint, 3> edges{minus(v[1], v[0]), minus(v[2], v[1]), minus(v[0], v[2])};
  if (separates(cross(edges[0], edges[1]))) return false;
  for (const RationalPoint& box_axis : box_axes) {
    for (const RationalPoint& edge : edges) {
      if (separates(cross(box_axis, edge))) return false;
    }
  }
  return true;
}

Decision decide_face_shape(const Shape& shape, const FaceShapeRows& rows, double thickness, const DecisionRequest& request) {
  if (!std::isfinite(thickness) || thickness < 0) throw std::invalid_argument("reference: δ must be finite and >= 0");
  const mpq_class delta(thickness);
  const std::array<RationalPoint, 3> face0{rational(rows.face_t0[0]), rational(rows.face_t0[1]), rational(rows.face_t0[2])};
  const std::array<RationalPoint, 3> face1{rational(rows.face_t1[0]), rational(rows.face_t1[1]), rational(rows.face_t1[2])};
  const RationalPoint c0 = rational(rows.centre_t0), c1 = rational(rows.centre_t1);

  if (shape.kind == ShapeKind::sphere) {
    if (!std::isfinite(shape.radius) || !(shape.radius > 0)) throw std::invalid_argument("reference: a sphere's radius must be finite and > 0");
    const ExactPair pair{PairKind::vertex_face, {c0, face0[0], face0[1], face0[2], c1, face1[0], face1[1], face1[2]}};
    return decide(pair, mpq_class(shape.radius) + delta, request);  // R + δ exactly
  }

  if (!shape.half_extents.allFinite() || !(shape.half_extents.minCoeff() > 0)) {
    throw std::invalid_argument("reference: a box's half extents must be finite and > 0");
  }
  const RationalPoint half = rational(shape.half_extents);
  Decision decision{false, DecidedBy::filter, std::nullopt, std::nullopt, std::nullopt};
  if (triangle_meets_box(face0, c0, half)) {
    decision.collides = true;
    decision.decided_by = DecidedBy::exact;
    if (request.want_toi) {
      decision.toi = RationalInterval{0, 0};
      decision.toi_floor = 0.0;
      decision.toi_ceiling = 0.0;
    }
    return decision;
  }
  // Exact corners: rational additions do not round.
  const std::array<RationalPoint, 8> corners0 = box_corners(c0, half), corners1 = box_corners(c1, half);
  for_each_box_surface_pair(face0, face1, corners0, corners1, [&](bool vertex_face, const std::array<RationalPoint, 8>& pair_rows) {
    merge(decision, decide(ExactPair{vertex_face ? PairKind::vertex_face : PairKind::edge_edge, pair_rows}, delta, request));
    return decision.collides && !request.want_toi;  // the earliest TOI needs every part
  });
  return decision;
}

}  // namespace ccd::reference
