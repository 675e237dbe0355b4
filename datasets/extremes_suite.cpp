#include "datasets/extremes_suite.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <random>

namespace ccd::datasets {
namespace {

using Rows = std::array<Vec3, 8>;

Rows vf(Vec3 p0, Vec3 a0, Vec3 b0, Vec3 c0, Vec3 p1, Vec3 a1, Vec3 b1, Vec3 c1) { return {p0, a0, b0, c0, p1, a1, b1, c1}; }
/// The unit triangle (0,0,0) (1,0,0) (0,1,0), still, against a point moving p0 -> p1.
Rows vf_still(Vec3 p0, Vec3 p1) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  return vf(p0, a, b, c, p1, a, b, c);
}
Rows ee(Vec3 a0, Vec3 a1, Vec3 b0, Vec3 b1, Vec3 a0e, Vec3 a1e, Vec3 b0e, Vec3 b1e) { return {a0, a1, b0, b1, a0e, a1e, b0e, b1e}; }
Rows ee_still(Vec3 a0, Vec3 a1, Vec3 b0, Vec3 b1) { return {a0, a1, b0, b1, a0, a1, b0, b1}; }

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

Rows transformed(Rows rows, const std::function<Vec3(const Vec3&)>& map) {
  for (Vec3& row : rows) row = map(row);
  return rows;
}
Rows translated(const Rows& rows, const Vec3& by) {
  return transformed(rows, [&](const Vec3& p) { return Vec3(p + by); });
}
Rows scaled(const Rows& rows, double by) {
  return transformed(rows, [&](const Vec3& p) { return Vec3(p * by); });
}

double size_of(const Rows& rows) {
  Vec3 lower = rows[0], upper = rows[0];
  for (const Vec3& r : rows) {
    lower = lower.cwiseMin(r);
    upper = upper.cwiseMax(r);
  }
  return (upper - lower).stableNorm();  // no overflow of the squares near DBL_MAX
}

struct Base {
  std::string family;
  std::string name;
  QueryKind kind;
  Rows rows;
  double positive_thickness;  // 0: 1e-3 of the case's size
};

std::vector<Base> base_cases() {
  std::vector<Base> cases;
  const auto VF = QueryKind::vertex_face;
  const auto EE = QueryKind::edge_edge;
  auto add = [&](const char* family, std::string name, QueryKind kind, Rows rows, double thickness = 0) {
    cases.push_back({family, std::move(name), kind, rows, thickness});
  };
  const double e23 = std::ldexp(1.0, -23);

  add("coplanar-motion", "vertex sweeping into the face in its plane", VF, vf_still({-1, 0.25, 0}, {0.25, 0.25, 0}));
  add("coplanar-motion", "vertex sweeping past the face in its plane", VF, vf_still({2, -1, 0}, {2, 1, 0}));
  add("coplanar-motion", "edges crossing in their common plane at t=1/2 only", EE,
      ee({-1, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 2, 0}, {-1, 0, 0}, {1, 0, 0}, {0, -2, 0}, {0, -1, 0}));
  add("coplanar-motion", "coplanar edges sliding past each other", EE,
      ee({0, 0, 0}, {1, 0, 0}, {2, 1, 0}, {3, 1, 0}, {0, 0, 0}, {1, 0, 0}, {-3, 1, 0}, {-2, 1, 0}));

  add("parallel-collinear", "parallel edges 1 apart", EE, ee_still({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}));
  add("parallel-collinear", "collinear overlapping edges", EE, ee_still({0, 0, 0}, {2, 0, 0}, {1, 0, 0}, {3, 0, 0}));
  add("parallel-collinear", "collinear edges with a gap", EE, ee_still({0, 0, 0}, {1, 0, 0}, {1.5, 0, 0}, {3, 0, 0}));
  add("parallel-collinear", "parallel edges closing in until they touch at t=1", EE,
      ee({0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {1.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, {0.5, 0, 0}, {1.5, 0, 0}));

  add("zero-motion", "still and apart", VF, vf_still({0.25, 0.25, 0.5}, {0.25, 0.25, 0.5}));
  add("zero-motion", "still and touching the face", VF, vf_still({0.25, 0.25, 0}, {0.25, 0.25, 0}));
  add("zero-motion", "still crossing edges", EE, ee_still({-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}));

  for (double perturbation : {0.0, e23, -e23}) {
    const std::string suffix = perturbation == 0 ? "" : perturbation > 0 ? " + 2^-23" : " - 2^-23";
    add("touch-at-t0-t1", "touching at t=0" + suffix, VF, vf_still({0.25, 0.25, perturbation}, {0.25, 0.25, 1}));
    add("touch-at-t0-t1", "touching at t=1" + suffix, VF, vf_still({0.25, 0.25, 1}, {0.25, 0.25, perturbation}));
    add("touch-at-t0-t1", "edges touching at t=1" + suffix, EE,
        ee({-1, 0, 1}, {1, 0, 1}, {0, -1, 0}, {0, 1, 0}, {-1, 0, perturbation}, {1, 0, perturbation}, {0, -1, 0}, {0, 1, 0}));
  }

  add("through-edge-or-corner", "vertex through a face edge", VF, vf_still({0.5, -1, 1}, {0.5, 1, -1}));
  add("through-edge-or-corner", "vertex through a face corner", VF, vf_still({-1, -1, 1}, {1, 1, -1}));
  add("through-edge-or-corner", "edge through the other's endpoint", EE,
      ee({-1, 0, 1}, {1, 0, 1}, {0, 0, 0}, {0, 1, 0}, {-1, 0, -1}, {1, 0, -1}, {0, 0, 0}, {0, 1, 0}));

  add("hourglass", "face degenerate at t=1/2 against a far point", VF,
      vf({0.5, 0, 10}, {0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 0, 10}, {0, 0, 0}, {1, 0, 0}, {0.5, -1, 0}));
  add("hourglass", "face degenerate at t=1/2 swept through a point on its line", VF,
      vf({0.25, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.25, 0, 0}, {0, 0, 0}, {1, 0, 0}, {0.5, -1, 0}));

  add("two-roots", "vertex entering and leaving the face plane inside the face", VF,
      vf({0.5, 0.5, 0.125}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0.1}, {0, 0, 0}, {1, 0, 1}, {1, 1, 0}));
  add("two-roots", "tangential double root at t=1/2", VF,
      vf({0.5, 0.5, 0.125}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0.125}, {0, 0, 0}, {1, 0, 1}, {1, 1, 0}));
  add("two-roots", "double root lifted by 2^-30: a miss", VF,
      vf({0.5, 0.5, 0.125 + std::ldexp(1.0, -30)}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0.125 + std::ldexp(1.0, -30)}, {0, 0, 0}, {1, 0, 1},
         {1, 1, 0}));

  for (double delta : {0.1, 1e-3}) {
    const double below = std::nextafter(delta, 0.0), above = std::nextafter(delta, 1.0);
    for (auto [label, distance] : {std::pair{"exactly δ", delta}, {"one ulp inside δ", below}, {"one ulp beyond δ", above}}) {
      const std::string at = std::string(" at ") + label + " (δ " + (delta == 0.1 ? "0.1)" : "1e-3)");
      add("exact-thickness", "edges crossing" + at, EE, ee_still({-1, 0, 0}, {1, 0, 0}, {0, -1, distance}, {0, 1, distance}), delta);
      add("exact-thickness", "vertex passing over the face" + at, VF, vf_still({-1, 0.25, distance}, {2, 0.25, distance}), delta);
    }
  }

  add("within-thickness-at-t0", "vertex 1e-4 above the face, moving away", VF, vf_still({0.25, 0.25, 1e-4}, {0.25, 0.25, 1}), 1e-3);
  add("within-thickness-at-t0", "edges 1e-4 apart, separating", EE,
      ee({-1, 0, 0}, {1, 0, 0}, {0, -1, 1e-4}, {0, 1, 1e-4}, {-1, 0, 0}, {1, 0, 0}, {0, -1, 1}, {0, 1, 1}), 1e-3);

  add("near-miss-1e-12", "vertex stopping 1e-12 short of the face", VF, vf_still({0.25, 0.25, 1}, {0.25, 0.25, 1e-12}));
  add("near-miss-1e-12", "vertex passing 1e-12 outside an edge", VF, vf_still({0.5, -1e-12, 1}, {0.5, -1e-12, -1}));
  add("near-miss-1e-12", "edges passing 1e-12 apart", EE,
      ee({-1, 0, 1}, {1, 0, 1}, {0, -1, 1e-12}, {0, 1, 1e-12}, {-1, 0, -1}, {1, 0, -1}, {0, -1, 1e-12 - 2}, {0, 1, 1e-12 - 2}));

  for (double scale : {1e-12, 1e-6, 1.0, 1e3, 1e9}) {
    // Positions of magnitude `scale`, moving by 1e-6 of it: a crossing and a miss.
    const double m = 1e-6 * scale;
    add("magnitudes", "crossing at scale " + number(scale), VF, vf_still({0.25 * scale, 0.25 * scale, m}, {0.25 * scale, 0.25 * scale, -m}));
    const Rows base = vf_still({0.25, 0.25, 1e-6}, {0.25, 0.25, -1e-6});
    add("magnitudes", "small crossing at magnitude " + number(scale), VF, translated(scaled(base, m), Vec3::Constant(scale)));
    add("magnitudes", "small miss at magnitude " + number(scale), VF,
        translated(scaled(vf_still({0.25, 0.25, 2e-6}, {0.25, 0.25, 1e-6}), m), Vec3::Constant(scale)));
  }

  add("tiny-next-to-one", "vertex at 1e-18 above the face, then through it", VF, vf_still({0.25, 0.25, 1e-18}, {0.25, 0.25, -1}));
  add("tiny-next-to-one", "face corner at 1 + 1e-18 (rounds to 1)", VF,
      vf({0.25, 0.25, 1}, {0, 0, 0}, {1 + 1e-18, 0, 0}, {0, 1, 0}, {0.25, 0.25, -1}, {0, 0, 0}, {1, 1e-18, 0}, {0, 1, 0}));
  add("tiny-next-to-one", "edges 1e-18 apart", EE, ee_still({-1, 0, 0}, {1, 0, 0}, {0, -1, 1e-18}, {0, 1, 1e-18}));

  for (double offset : {1e3, 1e6, 1e9}) {
    add("large-translation", "crossing moved by " + number(offset), EE,
        translated(ee({-1, 0, 1}, {1, 0, 1}, {0, -1, 0}, {0, 1, 0}, {-1, 0, -1}, {1, 0, -1}, {0, -1, 0}, {0, 1, 0}), Vec3(offset, -offset, offset)));
    add("large-translation", "near miss moved by " + number(offset), VF,
        translated(vf_still({1.25, 0.25, 1}, {1.25, 0.25, -1}), Vec3(offset, offset, -offset)));
  }

  add("degenerate-primitives", "zero-area face, point crossing its segment", VF,
      vf({0.5, -1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0.5, 1, 0}, {0, 0, 0}, {1, 0, 0}, {2, 0, 0}));
  add("degenerate-primitives", "zero-length edge crossing an edge", EE,
      ee({-1, 0, 0}, {1, 0, 0}, {0, 0, 1}, {0, 0, 1}, {-1, 0, 0}, {1, 0, 0}, {0, 0, -1}, {0, 0, -1}));
  add("degenerate-primitives", "sliver face hit near its long edge", VF,
      vf({0.5, 1e-9, 1}, {0, 0, 0}, {1, 0, 0}, {0.5, 1e-6, 0}, {0.5, 1e-9, -1}, {0, 0, 0}, {1, 0, 0}, {0.5, 1e-6, 0}));
  add("degenerate-primitives", "sliver face missed just beside it", VF,
      vf({0.5, 2e-6, 1}, {0, 0, 0}, {1, 0, 0}, {0.5, 1e-6, 0}, {0.5, 2e-6, -1}, {0, 0, 0}, {1, 0, 0}, {0.5, 1e-6, 0}));

  // The numerical extremes of double itself. Coordinates with few significant bits (0.25, 0.5, 0.75, 1.25, 2)
  // stay exact when scaled into the subnormal range.
  const Rows vf_cross = vf_still({0.25, 0.25, 1}, {0.25, 0.25, -1});
  const Rows vf_edge_miss = vf_still({0.5, -0.25, 1}, {0.5, -0.25, -1});
  const Rows vf_stop_short = vf_still({0.25, 0.25, 1}, {0.25, 0.25, 0.25});
  const Rows ee_cross = ee({-1, 0, 1}, {1, 0, 1}, {0, -1, 0}, {0, 1, 0}, {-1, 0, -1}, {1, 0, -1}, {0, -1, 0}, {0, 1, 0});
  const Rows ee_pass = ee({-1, 0, 1}, {1, 0, 1}, {2, -1, 0}, {2, 1, 0}, {-1, 0, -1}, {1, 0, -1}, {2, -1, 0}, {2, 1, 0});
  for (auto [family, exponent] : {std::pair{"smallest-normal", -1015}, {"subnormal", -1062}, {"near-max", 1020}}) {
    const std::string at = " at 2^" + std::to_string(exponent);
    add(family, "vertex through the face" + at, VF, scaled(vf_cross, std::ldexp(1.0, exponent)));
    add(family, "vertex passing outside an edge" + at, VF, scaled(vf_edge_miss, std::ldexp(1.0, exponent)));
    add(family, "vertex stopping short of the face" + at, VF, scaled(vf_stop_short, std::ldexp(1.0, exponent)));
    add(family, "edges crossing" + at, EE, scaled(ee_cross, std::ldexp(1.0, exponent)));
    add(family, "edges passing beside each other" + at, EE, scaled(ee_pass, std::ldexp(1.0, exponent)));
  }
  // Motion far larger than the features: the whole pair is carried 1e10 (an integer, exact) along an axis
  // during the step, while the features do what the base cases do.
  for (double carried : {1e10, -1e10}) {
    const Vec3 by(carried, 0, 0);
    auto carried_away = [&](Rows rows) {
      for (int k = 4; k < 8; ++k) rows[k] += by;
      return rows;
    };
    // δ > 0 at 1e-3 of the features (not of the swept box, which is 1e10 long).
    const std::string how = " while carried " + number(carried);
    add("huge-motion", "vertex through the face" + how, VF, carried_away(vf_cross), 1e-3);
    add("huge-motion", "vertex passing outside an edge" + how, VF, carried_away(vf_edge_miss), 1e-3);
    add("huge-motion", "vertex stopping short of the face" + how, VF, carried_away(vf_stop_short), 1e-3);
    add("huge-motion", "edges crossing" + how, EE, carried_away(ee_cross), 1e-3);
    add("huge-motion", "edges passing beside each other" + how, EE, carried_away(ee_pass), 1e-3);
  }
  return cases;
}

}  // namespace

std::optional<std::array<Vec3, 8>> scaled_exactly(const std::array<Vec3, 8>& rows, int exponent) {
  std::array<Vec3, 8> out = rows;
  for (Vec3& row : out) {
    for (int k = 0; k < 3; ++k) {
      const double value = std::ldexp(row[k], exponent);
      if (!std::isfinite(value) || (value != 0 && !std::isnormal(value)) || std::ldexp(value, -exponent) != row[k]) return std::nullopt;
      row[k] = value;
    }
  }
  return out;
}

std::vector<int> extremes_scale_exponents() { return {-1000, -960, -530, -515, 500, 960, 1000}; }

namespace {

std::string scaled_family(int exponent) { return "scaled-2^" + std::to_string(exponent); }

/// Families whose cases are already at an extreme of double, which rescaling would push out of range.
bool at_an_extreme(const std::string& family) {
  return family == "smallest-normal" || family == "subnormal" || family == "near-max" || family == "magnitudes" || family == "tiny-next-to-one" ||
         family == "large-translation" || family == "huge-motion";
}

}  // namespace

std::vector<std::string> extremes_families() {
  std::vector<std::string> families;
  for (const Base& base : base_cases()) {
    if (std::find(families.begin(), families.end(), base.family) == families.end()) families.push_back(base.family);
  }
  for (int exponent : extremes_scale_exponents()) families.push_back(scaled_family(exponent));
  return families;
}

std::vector<ExtremeQuery> extremes_suite(std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::vector<ExtremeQuery> suite;
  constexpr int kVariants = 6;
  for (const Base& base : base_cases()) {
    for (int variant = 0; variant <= kVariants; ++variant) {
      Rows rows = base.rows;
      std::string name = base.name;
      double scale = 1;
      if (variant > 0) {
        // Exact transformations only: permute axes, flip signs, reverse time, reorder corners or endpoints.
        std::array<int, 3> axes{0, 1, 2};
        std::shuffle(axes.begin(), axes.end(), random);
        std::array<double, 3> signs{};
        for (double& sign : signs) sign = random() % 2 ? 1.0 : -1.0;
        rows = transformed(rows, [&](const Vec3& p) { return Vec3(signs[0] * p[axes[0]], signs[1] * p[axes[1]], signs[2] * p[axes[2]]); });
        name += ", axes permuted and flipped";
        if (random() % 2) {
          for (int k = 0; k < 4; ++k) std::swap(rows[k], rows[k + 4]);
          name += ", time reversed";
        }
        if (random() % 2) {
          // VF: swap two face corners; EE: swap the two edges.
          if (base.kind == QueryKind::vertex_face) {
            std::swap(rows[2], rows[3]);
            std::swap(rows[6], rows[7]);
          } else {
            std::swap(rows[0], rows[2]);
            std::swap(rows[1], rows[3]);
            std::swap(rows[4], rows[6]);
            std::swap(rows[5], rows[7]);
          }
          name += ", reordered";
        }
        // Powers of two scale exactly (kept moderate so tiny and huge cases stay representable).
        if (!at_an_extreme(base.family) && random() % 2) {
          scale = std::ldexp(1.0, static_cast<int>(random() % 17) - 8);
          rows = scaled(rows, scale);
          name += ", scaled by 2^" + std::to_string(static_cast<int>(std::log2(scale)));
        }
      }
      const double positive = base.positive_thickness > 0 ? base.positive_thickness * scale : 1e-3 * size_of(rows);
      suite.push_back({base.family, name, base.kind, rows, positive});
    }
  }
  // Every other family at the scales of double's far ends, where the rescaling is exact (δ > 0 rescaled alike).
  for (int exponent : extremes_scale_exponents()) {
    for (const Base& base : base_cases()) {
      if (at_an_extreme(base.family)) continue;
      const std::optional<Rows> rows = scaled_exactly(base.rows, exponent);
      if (!rows) continue;
      const double positive = std::ldexp(base.positive_thickness > 0 ? base.positive_thickness : 1e-3 * size_of(base.rows), exponent);
      suite.push_back(
          {scaled_family(exponent), base.family + ": " + base.name + ", scaled by 2^" + std::to_string(exponent), base.kind, *rows, positive});
    }
  }
  return suite;
}

}  // namespace ccd::datasets
