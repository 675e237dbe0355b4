#pragma once
/// @file
/// Pairs for the scale tests of the conservative tests: the extremes suite (always), and the public data's small sets
/// (sample-queries and the cloth-funnel step; the rod-twist step adds time, not cases) in tests of their own, which
/// skip without the data: no test's threshold depends on whether the data is there.

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

/// The extremes suite's pairs, each with its own δ > 0.
inline std::vector<ScalePair> extremes_scale_pairs() {
  std::vector<ScalePair> pairs;
  for (const datasets::ExtremeQuery& query : datasets::extremes_suite(1)) {
    pairs.push_back({query.kind, query.rows, query.positive_thickness, query.family + ": " + query.name});
  }
  return pairs;
}

/// The public data's small sets under `data` (CCD_REQUIRE_EXTERNAL_DATA), with a small δ > 0 of each pair's size.
inline std::vector<ScalePair> public_data_scale_pairs(const std::filesystem::path& data) {
  std::vector<ScalePair> pairs;
  for (const auto& path : datasets::discover_query_files({data / "sample-queries", data / "scalable-ccd-sample/cloth-funnel"})) {
    const datasets::QueryFile file = datasets::read_query_file(path);
    for (const datasets::Query& query : file.queries) {
      pairs.push_back({file.kind, query.rounded, small_thickness_for(query.rounded), path.string() + ":" + std::to_string(query.first_line)});
    }
  }
  EXPECT_EQ(pairs.size(), shared_query_count("sample-queries") + shared_query_count("scalable-ccd-sample/cloth-funnel"));
  return pairs;
}

}  // namespace ccd::testing
