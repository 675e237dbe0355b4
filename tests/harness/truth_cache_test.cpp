// The truth cache: a file is used only when its checksum holds and every pair is one the scene can have; anything
// else is reported and the truth computed again.

#include "harness/truth_cache.hpp"
#include "ccd/source_digest.hpp"
#include "core/error.hpp"
#include "core/step.hpp"
#include "datasets/procedural_scenes.hpp"
#include "reference/elementary_pair.hpp"
#include "reference/step_truth.hpp"
#include "tests/support/cli.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

namespace ccd::harness {
namespace {

/// Two 5x5 sheets, the second passing down through the first during the step (self contact off on the second).
struct CrossingStep {
  Scene scene;
  std::vector<Vec3> x0, x1;
};

CrossingStep crossing_step() {
  std::vector<Face> faces = testing::grid_faces(5);
  std::vector<Vec3> x0 = testing::grid_positions(5, 0.0), x1 = x0;
  for (Vec3& p : x1) p.z() += 0.01 * p.x();  // the lower sheet bends a little
  for (const Vec3& p : testing::grid_positions(5, 0.0)) {
    x0.push_back(Vec3(0.3 + p.x() * 0.5, 0.2 + p.y() * 0.5, 0.5));
    x1.push_back(Vec3(0.35 + p.x() * 0.5, 0.25 + p.y() * 0.5, -0.5 + 0.02 * p.y()));
  }
  Scene scene({{"lower", ObjectKind::deformable, true, 25, faces}, {"upper", ObjectKind::deformable, false, 25, faces}}, {{0, 1}}, 0.0);
  return {std::move(scene), std::move(x0), std::move(x1)};
}

/// A 5x5 sheet with a sphere falling through it and a box rising into it: face-shape contacts beside VF and EE.
CrossingStep shape_crossing_step() {
  std::vector<Vec3> x0 = testing::grid_positions(5, 0.0), x1 = x0;
  for (Vec3& p : x1) p.z() += 0.05 * p.x();
  x0.push_back(Vec3(1.3, 1.6, 1.0));
  x1.push_back(Vec3(1.4, 1.5, -1.0));
  x0.push_back(Vec3(3.1, 2.2, -2.0));
  x1.push_back(Vec3(3.0, 2.3, 0.2));
  Scene scene({{"sheet", ObjectKind::deformable, true, 25, testing::grid_faces(5)},
               {"ball", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::sphere, 0.4, Vec3::Zero()}},
               {"block", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::box, 0.0, Vec3(0.3, 0.5, 0.25)}}},
              {{0, 1}, {0, 2}}, 0.0);
  return {std::move(scene), std::move(x0), std::move(x1)};
}

std::vector<char> file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::filesystem::path& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(TruthCache, EveryFlippedBitIsDetectedAndTheTruthComputedAgain) {
  testing::TempDir dir;
  const CrossingStep step = crossing_step();
  std::ostringstream warnings;
  const TruthCache cache(dir / "truth", &warnings);
  bool computed = false;
  const CollisionSet truth = cache.truth(step.scene, step.x0, step.x1, computed);
  ASSERT_TRUE(computed);
  ASSERT_GT(truth.vertex_face().size(), 0u) << "the step must collide for this test to mean anything";
  ASSERT_GT(truth.edge_edge().size(), 0u);
  const auto file = cache.file_for(step.scene, step.x0, step.x1);
  EXPECT_TRUE(read_truth_file(file, step.scene).collisions.same_pairs(truth));
  EXPECT_TRUE(cache.truth(step.scene, step.x0, step.x1, computed).same_pairs(truth));
  EXPECT_FALSE(computed);
  const std::vector<char> original = file_bytes(file);
  for (std::size_t byte = 0; byte < original.size(); ++byte) {
    for (int bit : {0, 7}) {
      std::vector<char> flipped = original;
      flipped[byte] = static_cast<char>(flipped[byte] ^ (1 << bit));
      write_bytes(file, flipped);
      EXPECT_THROW(read_truth_file(file, step.scene), InputError) << "byte " << byte << " bit " << bit;
    }
  }
  warnings.str("");
  const CollisionSet again = cache.truth(step.scene, step.x0, step.x1, computed);
  EXPECT_TRUE(computed) << "a corrupt file must be recomputed, not used";
  EXPECT_TRUE(again.same_pairs(truth));
  EXPECT_NE(warnings.str().find(file.filename().string()), std::string::npos) << warnings.str();
  EXPECT_EQ(file_bytes(file), original) << "the recomputed truth replaces the corrupt file";
}

// Face-shape pairs and their TOIs are kept like the others; every flipped bit is still detected; a face-shape
// pair the scene cannot have (a mesh object, or a shape it may not collide with) is refused.
TEST(TruthCache, FaceShapePairsAreCachedAndCheckedToo) {
  testing::TempDir dir;
  CrossingStep step = shape_crossing_step();
  const TruthCache cache(dir / "truth", nullptr);
  bool computed = false;
  const CollisionSet truth = cache.truth(step.scene, step.x0, step.x1, computed, true);
  ASSERT_TRUE(computed);
  std::set<ObjectId> shapes;
  for (const auto& c : truth.face_shape()) shapes.insert(c.pair.shape);
  ASSERT_EQ(shapes, (std::set<ObjectId>{1, 2})) << "both shapes must collide for this test to mean anything";
  const auto file = cache.file_for(step.scene, step.x0, step.x1);
  const CachedTruth cached = read_truth_file(file, step.scene);
  ASSERT_TRUE(cached.collisions.same_pairs(truth));
  for (std::size_t i = 0; i < truth.face_shape().size(); ++i) EXPECT_EQ(cached.collisions.face_shape()[i].toi, truth.face_shape()[i].toi);
  const std::vector<char> original = file_bytes(file);
  for (std::size_t byte = 0; byte < original.size(); ++byte) {
    std::vector<char> flipped = original;
    flipped[byte] = static_cast<char>(flipped[byte] ^ 1);
    write_bytes(file, flipped);
    EXPECT_THROW(read_truth_file(file, step.scene), InputError) << "byte " << byte;
  }
  // Another radius is another scene: its truth has another key.
  const auto key = truth_key(step.scene, step.x0, step.x1);
  Scene bigger({{"sheet", ObjectKind::deformable, true, 25, testing::grid_faces(5)},
                {"ball", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::sphere, 0.5, Vec3::Zero()}},
                {"block", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::box, 0.0, Vec3(0.3, 0.5, 0.25)}}},
               {{0, 1}, {0, 2}}, 0.0);
  EXPECT_NE(truth_key(bigger, step.x0, step.x1), key);
  auto refused = [&](FaceShapePair pair) {
    CollisionSet set;
    set.add(pair);
    write_truth_file(dir / "x.truth", set);
    return testing::error_message<InputError>([&] { read_truth_file(dir / "x.truth", step.scene); });
  };
  EXPECT_NE(refused({0, 0}).find("x.truth:face-shape pair 0: not a face-shape pair this scene can have"), std::string::npos);
  EXPECT_NE(refused({99, 1}).find("not a face-shape pair"), std::string::npos);
  EXPECT_NE(refused({0, 7}).find("not a face-shape pair"), std::string::npos);
  Scene apart({{"sheet", ObjectKind::deformable, true, 25, testing::grid_faces(5)},
               {"ball", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::sphere, 0.4, Vec3::Zero()}},
               {"block", ObjectKind::shape, false, 1, {}, Shape{ShapeKind::box, 0.0, Vec3(0.3, 0.5, 0.25)}}},
              {{0, 1}}, 0.0);
  CollisionSet block_pair;
  block_pair.add(FaceShapePair{0, 2});
  write_truth_file(dir / "y.truth", block_pair);
  EXPECT_NE(testing::error_message<InputError>([&] { read_truth_file(dir / "y.truth", apart); }).find("not a face-shape pair"), std::string::npos);
}

// A file with a valid checksum can still hold pairs of another scene: every pair is checked against this one (an
// out-of-range index used to crash `run` in record_misses).
TEST(TruthCache, PairsTheSceneCannotHaveAreRefused) {
  testing::TempDir dir;
  const CrossingStep step = crossing_step();
  const auto file = dir / "x.truth";
  auto refused = [&](const CollisionSet& set) {
    write_truth_file(file, set);
    return testing::error_message<InputError>([&] { read_truth_file(file, step.scene); });
  };
  CollisionSet out_of_range;
  out_of_range.add(VertexFacePair{1000000, 0});
  EXPECT_NE(refused(out_of_range).find("x.truth:vertex-face pair 0: vertex 1000000 or face 0 out of range"), std::string::npos);
  CollisionSet corner;
  corner.add(VertexFacePair{step.scene.topology().face(0)[1], 0});
  EXPECT_NE(refused(corner).find("not a vertex-face pair this scene can have"), std::string::npos);
  CollisionSet self_upper;  // the upper sheet has no self contact
  self_upper.add(VertexFacePair{25 + 12, 33});
  EXPECT_NE(refused(self_upper).find("not a vertex-face pair"), std::string::npos);
  CollisionSet not_an_edge;
  not_an_edge.add(EdgeEdgePair{{0, 24}, {25, 26}});
  EXPECT_NE(refused(not_an_edge).find("is not an edge of the mesh"), std::string::npos);
  {
    CollisionSet two;
    two.add(VertexFacePair{0, 20});
    two.add(VertexFacePair{0, 10});  // written in this order: out of order
    write_truth_file(file, two);
  }
  EXPECT_NE(testing::error_message<InputError>([&] { read_truth_file(file, step.scene); }).find("out of order"), std::string::npos);
}

TEST(TruthCache, CountsAreCheckedAgainstTheFileSizeBeforeAnythingIsAllocated) {
  testing::TempDir dir;
  const CrossingStep step = crossing_step();
  const auto file = dir / "x.truth";
  write_truth_file(file, CollisionSet{});
  std::vector<char> bytes = file_bytes(file);
  ASSERT_EQ(bytes.size(), 40u);
  bytes[15] = 0x10;  // the VF count becomes 2^60
  write_bytes(file, bytes);
  EXPECT_NE(testing::error_message<InputError>([&] { read_truth_file(file, step.scene); }).find("do not match the file's 40 bytes"),
            std::string::npos);
  write_bytes(file, {'C', 'C'});
  EXPECT_NE(testing::error_message<InputError>([&] { read_truth_file(file, step.scene); }).find("truncated"), std::string::npos);
}

// Exact TOIs are cached with the truth when asked for; a file without them is computed again when they are.
TEST(TruthCache, ExactToisAreCachedWithTheTruth) {
  testing::TempDir dir;
  const CrossingStep step = crossing_step();
  std::ostringstream warnings;
  const TruthCache cache(dir / "truth", &warnings);
  bool computed = false;
  const CollisionSet plain = cache.truth(step.scene, step.x0, step.x1, computed);
  EXPECT_TRUE(computed);
  EXPECT_FALSE(read_truth_file(cache.file_for(step.scene, step.x0, step.x1), step.scene).with_toi);
  const CollisionSet timed = cache.truth(step.scene, step.x0, step.x1, computed, true);
  EXPECT_TRUE(computed) << "a cached file without TOIs must be computed again with them";
  ASSERT_TRUE(timed.same_pairs(plain));
  const CachedTruth cached = read_truth_file(cache.file_for(step.scene, step.x0, step.x1), step.scene);
  ASSERT_TRUE(cached.with_toi);
  for (std::size_t i = 0; i < timed.vertex_face().size(); ++i) {
    EXPECT_EQ(cached.collisions.vertex_face()[i].toi, timed.vertex_face()[i].toi);
    const auto rows = pair_rows(step.scene.topology(), step.x0, step.x1, timed.vertex_face()[i].pair);
    EXPECT_EQ(timed.vertex_face()[i].toi, *reference::decide(reference::PairKind::vertex_face, rows, 0.0, {true, true, 64}).toi_floor);
  }
  EXPECT_TRUE(cache.truth(step.scene, step.x0, step.x1, computed, true).same_pairs(timed));
  EXPECT_FALSE(computed);
  EXPECT_TRUE(cache.truth(step.scene, step.x0, step.x1, computed, false).same_pairs(timed));
  EXPECT_FALSE(computed) << "a file with TOIs serves a request without them";
  EXPECT_EQ(warnings.str(), "");
}

// The key holds a digest of the reference's sources taken at build time: no version number to forget.
TEST(TruthCache, TheKeyHoldsTheDigestOfTheReferenceSources) {
  const std::string digest = CCDBENCH_REFERENCE_SOURCE_DIGEST;
  EXPECT_EQ(digest.size(), 64u) << digest;
  EXPECT_EQ(digest.find_first_not_of("0123456789abcdef"), std::string::npos) << digest;
  EXPECT_GE(CCDBENCH_REFERENCE_SOURCE_FILES, 20) << "the digest must cover reference/ and core/";
  EXPECT_NE(reference_version().find(CCDBENCH_REFERENCE_SOURCE_DIGEST), std::string::npos);
  const CrossingStep step = crossing_step();
  const std::string key = truth_key(step.scene, step.x0, step.x1);
  EXPECT_EQ(key.size(), 32u);
  std::vector<Vec3> moved = step.x1;
  moved[3].x() = std::nextafter(moved[3].x(), 9.0);
  EXPECT_NE(truth_key(step.scene, step.x0, moved), key);
  EXPECT_NE(truth_key(step.scene.with_thickness(1e-9), step.x0, step.x1), key);
}

// End to end: a bit flipped in every cached truth file used to change `missed`; now the run says so and its
// verdicts are those of the fresh truth.
TEST(TruthCache, ARunWithCorruptCachedTruthGivesTheSameVerdicts) {
  testing::TempDir dir;
  ::setenv("CCDBENCH_CACHE_DIR", (dir / "cache").c_str(), 1);
  datasets::generate_procedural_scene({"fold", {{"resolution", 6}, {"frames", 8}}, dir / "s", {}, {}});
  const std::string run = "run --strategy full --thickness 0 --scene " + testing::quoted(dir / "s") + " --fresh --out " +
                          testing::quoted(dir / "out") + " --json " + testing::quoted(dir / "s.json");
  const auto first = testing::run_ccdbench(run);
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const nlohmann::json before = testing::read_json(dir / "s.json");
  ASSERT_GT(before[0]["colliding"].get<int>(), 0);
  std::size_t corrupted = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "cache/truth")) {
    std::vector<char> bytes = file_bytes(entry.path());
    if (bytes.size() <= 40) continue;              // no pair to corrupt
    bytes[32] = static_cast<char>(bytes[32] ^ 1);  // the first pair's vertex: another pair, a valid-looking file
    write_bytes(entry.path(), bytes);
    ++corrupted;
  }
  ASSERT_GT(corrupted, 0u);
  const auto second = testing::run_ccdbench(run);
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_NE(second.output.find("the cached truth is not used"), std::string::npos) << second.output;
  const nlohmann::json after = testing::read_json(dir / "s.json");
  for (const char* field : {"colliding", "missed", "false_alarms", "reported"}) EXPECT_EQ(after[0][field], before[0][field]) << field;
  ::unsetenv("CCDBENCH_CACHE_DIR");
}

}  // namespace
}  // namespace ccd::harness
