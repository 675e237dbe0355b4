#pragma once
/// @file
/// Pairs for the scale tests of the conservative tests: the extremes suite and, when present, the public data's
/// small sets (sample-queries and the cloth-funnel step; the rod-twist step adds time, not cases).

#include "datasets/extremes_suite.hpp"
#include "datasets/query_file.hpp"
#include "tests/support/test_support.hpp"

#include <string>
#include <vector>

namespace ccd::testing {

struct ScalePair {
  datasets::QueryKind kind;
  std::array<Vec3, 8> rows;
  /// The δ > 0 of the pair's second pass.
  double positive_thickness;
  std::string where;
};

inline std::vector<ScalePair> scale_test_pairs() {
  std::vector<ScalePair> pairs;
  for (const datasets::ExtremeQuery& query : datasets::extremes_suite(1)) {
    pairs.push_back({query.kind, query.rows, query.positive_thickness, query.family + ": " + query.name});
  }
  std::string reason;
  if (const auto data = external_data_or_reason(reason)) {
    for (const auto& path : datasets::discover_query_files({*data / "sample-queries", *data / "scalable-ccd-sample/cloth-funnel"})) {
      const datasets::QueryFile file = datasets::read_query_file(path);
      for (const datasets::Query& query : file.queries) {
        pairs.push_back({file.kind, query.rounded, small_thickness_for(query.rounded), path.string() + ":" + std::to_string(query.first_line)});
      }
    }
  }
  return pairs;
}

}  // namespace ccd::testing
