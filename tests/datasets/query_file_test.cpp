#include "datasets/query_file.hpp"
#include "core/error.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

namespace ccd::datasets {
namespace {

using testing::TempDir;
using testing::write_text;

/// 8 rows of one query: `columns` per row, truth `t` in column 7 when asked.
std::string query_rows(int truth = -1, const std::string& coordinate = "1,2,-3,4,0,1") {
  std::string text;
  const std::string label = truth >= 0 ? std::string(",").append(std::to_string(truth)) : std::string();
  for (int r = 0; r < 8; ++r) text.append(coordinate).append(label).append("\n");
  return text;
}

std::string error_of(const std::filesystem::path& path) {
  try {
    read_query_file(path);
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

TEST(QueryPaths, KindFollowsFolderOrSuffix) {
  EXPECT_EQ(classify_query_path("a/vertex-face/data_0_0.csv"), QueryKind::vertex_face);
  EXPECT_EQ(classify_query_path("a/edge-edge/x/data.csv"), QueryKind::edge_edge);
  EXPECT_EQ(classify_query_path("queries/227vf.csv"), QueryKind::vertex_face);
  EXPECT_EQ(classify_query_path("queries/227ee.csv"), QueryKind::edge_edge);
  EXPECT_FALSE(classify_query_path("queries/227.csv").has_value());
  EXPECT_EQ(truth_file_for("d/queries/227vf.csv"), std::filesystem::path("d/mma_bool/227vf_mma_bool.json"));
  EXPECT_FALSE(truth_file_for("d/vertex-face/a.csv").has_value());
}

TEST(QueryFile, SevenColumnsWithoutFinalNewlineKeepExactRationalsAndDoubles) {
  TempDir dir;
  std::string text = query_rows(1) + query_rows(0, "1,3,0,1,5,1");
  text.pop_back();
  write_text(dir / "vertex-face/q.csv", text);
  const QueryFile file = read_query_file(dir / "vertex-face/q.csv");
  ASSERT_EQ(file.queries.size(), 2u);
  EXPECT_EQ(file.kind, QueryKind::vertex_face);
  EXPECT_TRUE(file.has_truth());
  EXPECT_EQ(file.positives(), 1u);
  EXPECT_EQ(file.queries[0].exact[3][1], mpq_class(-3, 4));
  EXPECT_EQ(file.queries[0].rounded[3][1], -0.75);
  EXPECT_TRUE(file.queries[0].exactly_double);
  EXPECT_EQ(file.queries[1].exact[0][0], mpq_class(1, 3));
  EXPECT_FALSE(file.queries[1].exactly_double);
  EXPECT_EQ(file.not_exactly_double(), 1u);
  EXPECT_EQ(file.queries[1].first_line, 9u);
}

TEST(QueryFile, WriteReadRoundTripKeepsExactValues) {
  TempDir dir;
  write_text(dir / "in/edge-edge/q.csv", query_rows(1, "-7,3,123456789012345678901234567890,7,0,1"));
  const QueryFile file = read_query_file(dir / "in/edge-edge/q.csv");
  write_query_file(dir / "out/edge-edge/q.csv", file.queries);
  const QueryFile back = read_query_file(dir / "out/edge-edge/q.csv");
  ASSERT_EQ(back.queries.size(), 1u);
  EXPECT_EQ(back.queries[0].exact, file.queries[0].exact);
  EXPECT_EQ(back.queries[0].truth, true);
}

// Labels for another thickness than 0 (a run's misses at δ, a comparison's newly missed pairs) say so on the first
// line, and read back exactly; any other comment, or this one elsewhere or on unlabelled rows, is bad input.
TEST(QueryFile, LabelsForAThicknessSaySoOnTheFirstLine) {
  TempDir dir;
  write_text(dir / "in/edge-edge/q.csv", query_rows(1, "-7,3,1,7,0,1"));
  const QueryFile file = read_query_file(dir / "in/edge-edge/q.csv");
  EXPECT_EQ(file.labels_thickness, 0.0);
  write_query_file(dir / "out/edge-edge/q.csv", file.queries, 0.1);
  const QueryFile back = read_query_file(dir / "out/edge-edge/q.csv");
  EXPECT_EQ(back.labels_thickness, 0.1);
  EXPECT_EQ(back.queries[0].exact, file.queries[0].exact);
  write_text(dir / "bad/edge-edge/second.csv", query_rows(1, "-7,3,1,7,0,1") + "# labels at thickness 0.1\n");
  EXPECT_NE(error_of(dir / "bad/edge-edge/second.csv").find("the only comment a query file may hold is its first line"), std::string::npos);
  write_text(dir / "bad/edge-edge/other.csv", "# a note\n" + query_rows(1, "-7,3,1,7,0,1"));
  EXPECT_NE(error_of(dir / "bad/edge-edge/other.csv").find("other.csv:line 1"), std::string::npos);
  write_text(dir / "bad/edge-edge/nan.csv", "# labels at thickness nan\n" + query_rows(1, "-7,3,1,7,0,1"));
  EXPECT_NE(error_of(dir / "bad/edge-edge/nan.csv").find("is not a thickness"), std::string::npos);
}

TEST(QueryFile, SixColumnsTakeTruthFromMmaBoolFile) {
  TempDir dir;
  write_text(dir / "queries/5vf.csv", query_rows() + query_rows());
  write_text(dir / "mma_bool/5vf_mma_bool.json", "[true, false]");
  const QueryFile file = read_query_file(dir / "queries/5vf.csv");
  EXPECT_EQ(file.positives(), 1u);
  EXPECT_EQ(file.truth_file, dir / "mma_bool/5vf_mma_bool.json");
  write_text(dir / "queries/6vf.csv", query_rows());
  EXPECT_FALSE(read_query_file(dir / "queries/6vf.csv").has_truth());
}

TEST(QueryFileBadInput, WrongColumnCount) {
  TempDir dir;
  std::string text = query_rows(1);
  text.replace(text.find("1,2,-3,4,0,1,1\n", 15), 15, "1,2,-3,4,0,1\n");
  write_text(dir / "vertex-face/q.csv", text);
  const std::string error = error_of(dir / "vertex-face/q.csv");
  EXPECT_NE(error.find("q.csv:line 2"), std::string::npos) << error;
  EXPECT_NE(error.find("columns"), std::string::npos) << error;
  write_text(dir / "vertex-face/five.csv", "1,2,3,4,5\n");
  EXPECT_NE(error_of(dir / "vertex-face/five.csv").find("6 or 7 columns"), std::string::npos);
}

TEST(QueryFileBadInput, ZeroDenominator) {
  TempDir dir;
  write_text(dir / "vertex-face/q.csv", query_rows(1) + "1,1,1,0,1,1,1\n" + query_rows(1).substr(15 * 1));
  const std::string error = error_of(dir / "vertex-face/q.csv");
  EXPECT_NE(error.find("line 9"), std::string::npos) << error;
  EXPECT_NE(error.find("zero denominator"), std::string::npos) << error;
}

TEST(QueryFileBadInput, RowCountNotAMultipleOfEight) {
  TempDir dir;
  write_text(dir / "vertex-face/q.csv", query_rows(0) + "1,1,1,1,1,1,0\n");
  EXPECT_NE(error_of(dir / "vertex-face/q.csv").find("not a multiple of 8"), std::string::npos);
}

TEST(QueryFileBadInput, TruthThatChangesWithinAQueryOrIsNotABit) {
  TempDir dir;
  std::string text = query_rows(1);
  text.replace(text.rfind(",1\n"), 3, ",0\n");
  write_text(dir / "vertex-face/q.csv", text);
  EXPECT_NE(error_of(dir / "vertex-face/q.csv").find("line 8"), std::string::npos);
  write_text(dir / "vertex-face/r.csv", query_rows(2));
  EXPECT_NE(error_of(dir / "vertex-face/r.csv").find("0 or 1"), std::string::npos);
}

TEST(QueryFileBadInput, TruthFileOfTheWrongLength) {
  TempDir dir;
  write_text(dir / "queries/5vf.csv", query_rows() + query_rows());
  write_text(dir / "mma_bool/5vf_mma_bool.json", "[true, false, true]");
  const std::string error = error_of(dir / "queries/5vf.csv");
  EXPECT_NE(error.find("5vf_mma_bool.json"), std::string::npos) << error;
  EXPECT_NE(error.find("3 entries"), std::string::npos) << error;
}

TEST(QueryFileBadInput, NonIntegersAndUnknownKind) {
  TempDir dir;
  write_text(dir / "vertex-face/q.csv", query_rows(1, "1,2,0.5,1,0,1"));
  EXPECT_NE(error_of(dir / "vertex-face/q.csv").find("not an integer: '0.5'"), std::string::npos);
  write_text(dir / "q.csv", query_rows(1));
  EXPECT_NE(error_of(dir / "q.csv").find("cannot tell"), std::string::npos);
}

TEST(QueryDiscovery, DirectoriesYieldCsvFilesOnly) {
  TempDir dir;
  write_text(dir / "vertex-face/a.csv", query_rows(1));
  write_text(dir / "vertex-face/readme.txt", "not a query");
  write_text(dir / "edge-edge/b.csv", query_rows(1));
  const auto files = discover_query_files({dir.path()});
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].filename(), "b.csv");
  EXPECT_THROW(discover_query_files({dir / "missing"}), InputError);
}

struct SharedQueryCount {
  const char* path;
  std::size_t queries;
  std::size_t positives;
};

// The counts of docs/DATA.md.
TEST(QueryFileSharedData, CountsMatchTheDataReadme) {
  CCD_REQUIRE_EXTERNAL_DATA(data);
  std::size_t vf_queries = 0, vf_positives = 0, ee_queries = 0, ee_positives = 0;
  for (const auto& path : discover_query_files({data / "sample-queries"})) {
    const QueryFile file = read_query_file(path);
    ASSERT_TRUE(file.has_truth()) << path;
    (file.kind == QueryKind::vertex_face ? vf_queries : ee_queries) += file.queries.size();
    (file.kind == QueryKind::vertex_face ? vf_positives : ee_positives) += file.positives();
  }
  EXPECT_EQ(vf_queries, 250u);
  EXPECT_EQ(vf_positives, 124u);
  EXPECT_EQ(ee_queries, 74u);
  EXPECT_EQ(ee_positives, 36u);
  for (const SharedQueryCount& expected :
       {SharedQueryCount{"cloth-funnel/queries/227vf.csv", 92, 27}, SharedQueryCount{"cloth-funnel/queries/227ee.csv", 263, 107},
        SharedQueryCount{"rod-twist/queries/3036vf.csv", 801, 765}, SharedQueryCount{"rod-twist/queries/3036ee.csv", 4370, 4179}}) {
    const QueryFile file = read_query_file(data / "scalable-ccd-sample" / expected.path);
    EXPECT_EQ(file.queries.size(), expected.queries) << expected.path;
    EXPECT_EQ(file.positives(), expected.positives) << expected.path;
    EXPECT_TRUE(file.truth_file.has_value()) << expected.path;
  }
}

}  // namespace
}  // namespace ccd::datasets
