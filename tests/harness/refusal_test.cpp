// What ccdbench refuses, and how: FILE:WHERE: REASON, exit status 2, before any work and without half-written
// output.

#include "datasets/procedural_scenes.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

namespace ccd {
namespace {

using testing::quoted;
using testing::run_ccdbench;

class Refusal : public ::testing::Test {
 protected:
  void SetUp() override { ::setenv("CCDBENCH_CACHE_DIR", (dir_ / "cache").c_str(), 1); }
  void TearDown() override { ::unsetenv("CCDBENCH_CACHE_DIR"); }

  /// Expects exit status 2 and `text` in what was printed.
  void expect_refused(const std::string& arguments, const std::string& text) {
    const testing::CommandResult result = run_ccdbench(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments << "\n" << result.output;
    EXPECT_NE(result.output.find(text), std::string::npos) << arguments << "\n" << result.output;
  }

  testing::TempDir dir_;
};

// A query file without labels used to score "positives 0, FN 0": a perfect score nobody measured.
TEST_F(Refusal, QueriesWithoutLabelsAreAnErrorUnlessAllowedAndThenNeverScoreZero) {
  // A vertex passing down through a triangle: 8 rows of x, y, z as numerator,denominator; no truth column.
  const std::string face = "0,1,0,1,0,1\n1,1,0,1,0,1\n0,1,1,1,0,1\n";
  const std::string rows = "1,4,1,4,1,1\n" + face + "1,4,1,4,-1,1\n" + face;
  testing::write_text(dir_ / "queries/unlabelled.csv", rows);  // 6 columns, no mma_bool beside it
  // The path rule cannot tell the kind of queries/NAME.csv; name it *vf.csv.
  std::filesystem::rename(dir_ / "queries/unlabelled.csv", dir_ / "queries/unlabelledvf.csv");
  const std::string vf = quoted(dir_ / "queries/unlabelledvf.csv");
  expect_refused("queries " + vf + " --method cubic32", "unlabelledvf.csv: 1 of 1 queries have no truth label");
  const testing::CommandResult allowed =
      run_ccdbench("queries " + vf + " --method cubic32 --allow-unlabelled --json " + quoted(dir_ / "scores.json"));
  ASSERT_EQ(allowed.exit_code, 0) << allowed.output;
  EXPECT_NE(allowed.output.find("1 of 1 queries had no truth label"), std::string::npos) << allowed.output;
  const nlohmann::json scores = testing::read_json(dir_ / "scores.json");
  for (const auto& score : scores) {
    EXPECT_TRUE(score["false_negatives"].is_null()) << score.dump();
    EXPECT_TRUE(score["false_positives"].is_null()) << score.dump();
    EXPECT_TRUE(score["positives"].is_null()) << score.dump();
    EXPECT_EQ(score["unlabelled"], 1);
  }
  // The table shows '-' where the count is unknown.
  const std::string table_row = allowed.output.substr(allowed.output.find("(all)"));
  EXPECT_NE(table_row.find(" - "), std::string::npos) << table_row;
}

TEST_F(Refusal, OutOfRangeKeysAndFlagsNameTheirRange) {
  datasets::generate_procedural_scene({"fold", {{"resolution", 5}, {"frames", 3}}, dir_ / "s", {}, {}});
  const std::string run = "run --scene " + quoted(dir_ / "s") + " --out " + quoted(dir_ / "out") + " --strategy ";
  // 1e300 iterations used to convert to a negative count and report every query colliding.
  expect_refused(run + "'full:max_iterations=1e300'", "max_iterations=1e300 must be an integer in [1, 1e+09]");
  expect_refused(run + "'full:tolerance=2'", "tolerance=2 must be a number in [0, 1]");
  expect_refused(run + "'apccd:nf_max=2147483648'", "nf_max=2147483648 must be an integer in [1, 1000]");
  expect_refused(run + "'apccd:nf_min=2.5'", "nf_min=2.5 must be an integer");
  expect_refused("queries " + quoted(dir_.path()) + " --method 'conservative:max_iterations=1e300'", "max_iterations=1e300");
  // apccd's own key misspelt: blamed on apccd, with both lists.
  expect_refused(run + "'apccd:foo=1'", "apccd+conservative has no parameter 'foo' (apccd's: skip,");
  expect_refused(
      run + "'full:nf_max=3'",
      "full+conservative has no parameter 'nf_max' (full's: backend, device, device_iterations, list_start, sub_boxes, memory, filter; narrow "
      "phase conservative's: tolerance, toi_tolerance, max_iterations)");
  // --threads 4294967297 used to wrap to 1, --threads 1e8 to allocate gigabytes.
  expect_refused("--threads 4294967297 scenes", "--threads");
  expect_refused("--threads 100000000 scenes", "--threads");
  expect_refused("--threads 0 scenes", "--threads");
  expect_refused(run + "full --repeat 0", "--repeat");
  expect_refused(run + "full --thickness -1", "--thickness");
  expect_refused(run + "full --thickness 1e999", "--thickness");
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out/results.jsonl"));
}

TEST_F(Refusal, BadFilesNameTheFileAndWhere) {
  testing::write_text(dir_ / "big/scene.json", "{\"thickness\": 1e999,\n \"objects\": []}");
  expect_refused("run --scene " + quoted(dir_ / "big") + " --out " + quoted(dir_ / "out"),
                 "scene.json:line 1: number 1e999 is beyond the range of double");
  // Folders where files are expected.
  std::filesystem::create_directories(dir_ / "a.ply");
  std::filesystem::create_directories(dir_ / "b.ply");
  expect_refused("run --frames " + quoted(dir_ / "a.ply") + " " + quoted(dir_ / "b.ply") + " --out " + quoted(dir_ / "out"),
                 "a.ply: is a folder, expected a PLY file");
  expect_refused("inspect " + quoted(dir_ / "a.ply"), "a.ply");
  // An empty mesh (FCL's endModel used to fail with a raw code).
  const std::string empty =
      "ply\nformat ascii 1.0\nelement vertex 0\nproperty double x\nproperty double y\n"
      "property double z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
  testing::write_text(dir_ / "e0.ply", empty);
  testing::write_text(dir_ / "e1.ply", empty);
  for (const char* strategy : {"fcl", "full"}) {
    expect_refused("run --strategy " + std::string(strategy) + " --frames " + quoted(dir_ / "e0.ply") + " " + quoted(dir_ / "e1.ply") + " --out " +
                       quoted(dir_ / "out"),
                   "e0.ply:faces: the mesh has no triangles");
  }
  // A simulation that diverges names the scene and the parameter that was changed.
  testing::write_text(dir_ / "wind/scene.json", R"({"generator": {"name": "flag", "resolution": 6, "frames": 4, "wind": 1e200}})");
  expect_refused("run --scene " + quoted(dir_ / "wind") + " --out " + quoted(dir_ / "out"),
                 "scene.json:generator: the simulation of 'flag' diverged at frame 1");
  expect_refused("run --scene " + quoted(dir_ / "wind") + " --out " + quoted(dir_ / "out"), "wind=1e+200 (default 8)");
  // A scene that cannot fit in memory is refused before anything is allocated (it used to end in std::bad_alloc).
  testing::write_text(dir_ / "huge/scene.json", R"({"generator": {"name": "pile", "resolution": 4096, "count": 64}})");
  expect_refused("run --scene " + quoted(dir_ / "huge") + " --out " + quoted(dir_ / "out"), "GiB to simulate");
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out/results.jsonl"));
}

TEST_F(Refusal, UnwritableOutputsAreFoundBeforeAnyWork) {
  datasets::generate_procedural_scene({"fold", {{"resolution", 5}, {"frames", 3}}, dir_ / "s", {}, {}});
  testing::write_text(dir_ / "file.txt", "not a folder");
  const std::string run = "run --strategy full --scene " + quoted(dir_ / "s");
  expect_refused(run + " --out " + quoted(dir_ / "file.txt"), "file.txt: cannot write output here: it is a file");
  expect_refused(run + " --out " + quoted(dir_ / "out") + " --json " + quoted(dir_ / "file.txt/s.json"), "file.txt");
  expect_refused(run + " --out " + quoted(dir_ / "out") + " --json " + quoted(dir_ / "s"), "s: cannot write output here: it is a folder");
  expect_refused(run + " --out " + quoted(dir_ / "out") + " --report " + quoted(dir_ / "file.txt"), "file.txt");
  expect_refused(run + " --out " + quoted(dir_ / "out") + " --misses " + quoted(dir_ / "file.txt/m"), "file.txt");
  EXPECT_FALSE(std::filesystem::exists(dir_ / "cache/truth")) << "no truth may be computed before the outputs are checked";
  expect_refused("truth --scene " + quoted(dir_ / "s") + " --json " + quoted(dir_ / "file.txt/t.json"), "file.txt");
  expect_refused("stress --json " + quoted(dir_ / "file.txt/x.json"), "file.txt");
}

// Frames given as ../c0.ply used to put --misses files outside the folder (the label began with "..").
TEST_F(Refusal, MissesStayInsideTheirFolder) {
  datasets::generate_procedural_scene({"fold", {{"resolution", 8}, {"frames", 24}}, dir_ / "g", {}, {}});
  std::filesystem::create_directories(dir_ / "work/inside");
  const std::string frames = "--frames ../c0.ply ../c1.ply";
  std::size_t misses_written = 0;
  for (int step = 0; step < 23 && misses_written == 0; ++step) {
    char a[64], b[64];
    std::snprintf(a, sizeof a, "g/sheet/frame_%04d.ply", step);
    std::snprintf(b, sizeof b, "g/sheet/frame_%04d.ply", step + 1);
    std::filesystem::copy_file(dir_ / a, dir_ / "work/c0.ply", std::filesystem::copy_options::overwrite_existing);
    std::filesystem::copy_file(dir_ / b, dir_ / "work/c1.ply", std::filesystem::copy_options::overwrite_existing);
    const auto result = run_ccdbench("run --strategy 'full+cubic32:eta=0' " + frames + " --fresh --out out --misses m", dir_ / "work/inside");
    ASSERT_EQ(result.exit_code, 0) << result.output;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(dir_.path())) {
      if (entry.path().extension() != ".csv") continue;
      const std::string path = std::filesystem::relative(entry.path(), dir_.path()).string();
      EXPECT_EQ(path.rfind("work/inside/m/", 0), 0u) << "a misses file outside --misses: " << path;
      ++misses_written;
    }
  }
  EXPECT_GT(misses_written, 0u) << "cubic32 must miss something on the fold for this test to mean anything";
}

}  // namespace
}  // namespace ccd
