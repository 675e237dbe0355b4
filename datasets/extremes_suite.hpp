#pragma once
/// @file
/// The extremes suite: named families of degenerate and extreme vertex-face and edge-edge queries, the cases
/// that break elementary tests. Queries are unlabelled here; the harness labels them with the exact reference.

#include "core/vec.hpp"
#include "datasets/query_file.hpp"

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace ccd::datasets {

struct ExtremeQuery {
  std::string family;
  /// What the case is, e.g. "vertex through the face's corner, time reversed".
  std::string name;
  QueryKind kind;
  /// Doubles, so every coordinate is exactly the rational the query files carry.
  std::array<Vec3, 8> rows;
  /// The thickness of the suite's δ > 0 pass for this case: 1e-3 of its size, or the δ the case is built on.
  double positive_thickness;
};

/// The family names, in the order the suite lists them.
std::vector<std::string> extremes_families();

/// The rows times 2^exponent when every coordinate stays a normal (or zero), finite double: then the scaling is
/// exact and the pair is the same question at another scale (at δ = 0 the same truth; at δ > 0 with δ scaled
/// alike). nullopt otherwise.
std::optional<std::array<Vec3, 8>> scaled_exactly(const std::array<Vec3, 8>& rows, int exponent);

/// The powers of two of the `scaled-2^K` families: every family not already at an extreme of double, rescaled
/// exactly (each coordinate stays a normal double) by 2^K.
std::vector<int> extremes_scale_exponents();

/// The whole suite. Each hand-built case also appears under exact transformations (axis permutations, sign
/// flips, time reversal, reordered corners or endpoints, power-of-two scaling), chosen with `seed`; all of them
/// keep every coordinate exact, so degenerate cases stay degenerate. Families at double's extremes: coordinates
/// near the smallest normal double, subnormal, near DBL_MAX, a pair carried 1e10 during the step (motion far
/// larger than its features), and every other case rescaled to 2^-1000 .. 2^1000 (the `scaled-2^K` families).
std::vector<ExtremeQuery> extremes_suite(std::uint64_t seed = 1);

}  // namespace ccd::datasets
