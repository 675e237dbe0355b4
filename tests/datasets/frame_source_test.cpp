#include "datasets/frame_source.hpp"
#include "core/error.hpp"
#include "datasets/mesh_file.hpp"
#include "datasets/mesh_frame.hpp"
#include "datasets/scene_sequence.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

namespace ccd::datasets {
namespace {

using testing::TempDir;

MeshFrame grid_frame(std::size_t n, double z) { return {testing::grid_positions(n, z), testing::grid_faces(n), ""}; }

std::string error_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

TEST(FrameFiles, DirectoryAndPatternListFramesInNumericOrder) {
  TempDir dir;
  for (int k : {0, 1, 2, 10, 3, 4, 5, 6, 7, 8, 9}) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.ply", k);
    write_mesh(dir / name, grid_frame(3, k));
  }
  const auto from_directory = expand_frame_files(dir.path());
  ASSERT_EQ(from_directory.size(), 11u);
  EXPECT_EQ(from_directory[10].filename(), "frame_0010.ply");
  EXPECT_EQ(expand_frame_files(dir / "frame_%04d.ply"), from_directory);
  const auto source = make_file_frame_source(from_directory);
  EXPECT_EQ(source->num_frames(), 11u);
  EXPECT_EQ(source->frame(7)[0].z(), 7.0);
}

TEST(FrameFiles, PatternStartsAtOneWhenThereIsNoFrameZero) {
  TempDir dir;
  write_mesh(dir / "f1.obj", grid_frame(2, 1));
  write_mesh(dir / "f2.obj", grid_frame(2, 2));
  EXPECT_EQ(expand_frame_files(dir / "f%d.obj").size(), 2u);
}

TEST(FrameFilesBadInput, GapsMixedNamesAndBadPatterns) {
  TempDir dir;
  write_mesh(dir / "frame_0000.ply", grid_frame(2, 0));
  write_mesh(dir / "frame_0002.ply", grid_frame(2, 0));
  EXPECT_NE(error_of([&] { expand_frame_files(dir.path()); }).find("frame 1 is missing"), std::string::npos);
  write_mesh(dir / "other_0001.ply", grid_frame(2, 0));
  EXPECT_NE(error_of([&] { expand_frame_files(dir.path()); }).find("different names"), std::string::npos);
  EXPECT_NE(error_of([&] { expand_frame_files(dir / "frame_%s.ply"); }).find("integer conversions"), std::string::npos);
  EXPECT_NE(error_of([&] { expand_frame_files(dir / "none_%d.ply"); }).find("no frame file"), std::string::npos);
}

// A pattern used to stop at the first missing number: frames 0 and 2 silently gave one frame.
TEST(FrameFilesBadInput, APatternWithAGapIsAnError) {
  TempDir dir;
  write_mesh(dir / "frame_0000.ply", grid_frame(2, 0));
  write_mesh(dir / "frame_0002.ply", grid_frame(2, 0));
  const std::string error = error_of([&] { expand_frame_files(dir / "frame_%04d.ply"); });
  EXPECT_NE(error.find("frame 1 is missing but frame 2 exists"), std::string::npos) << error;
  write_mesh(dir / "frame_0001.ply", grid_frame(2, 0));
  EXPECT_EQ(expand_frame_files(dir / "frame_%04d.ply").size(), 3u);
}

// frame_0001 and frame_01 used to give one of them, silently.
TEST(FrameFilesBadInput, TwoFilesWithOneNumberAreAnError) {
  TempDir dir;
  write_mesh(dir / "frame_0000.ply", grid_frame(2, 0));
  write_mesh(dir / "frame_0001.ply", grid_frame(2, 0));
  write_mesh(dir / "frame_01.ply", grid_frame(2, 1));
  const std::string listed = error_of([&] { expand_frame_files(dir.path()); });
  EXPECT_NE(listed.find("two files for frame 1"), std::string::npos) << listed;
  const std::string pattern = error_of([&] { expand_frame_files(dir / "frame_%04d.ply"); });
  EXPECT_NE(pattern.find("two files for frame 1"), std::string::npos) << pattern;
  std::filesystem::remove(dir / "frame_0001.ply");
  const std::string padding = error_of([&] { expand_frame_files(dir / "frame_%04d.ply"); });
  EXPECT_NE(padding.find("not padded as the pattern says"), std::string::npos) << padding;
}

// A folder named like a frame used to be skipped (and the frames after it with it, for a pattern).
TEST(FrameFilesBadInput, AFolderNamedLikeAFrameIsAnError) {
  TempDir dir;
  write_mesh(dir / "frame_0000.ply", grid_frame(2, 0));
  std::filesystem::create_directories(dir / "frame_0001.ply");
  write_mesh(dir / "frame_0002.ply", grid_frame(2, 0));
  for (const auto& path : {dir.path(), dir / "frame_%04d.ply"}) {
    const std::string error = error_of([&] { expand_frame_files(path); });
    EXPECT_NE(error.find("frame_0001.ply: is named like a frame file but is not a regular file"), std::string::npos) << error;
  }
}

TEST(FrameFilesBadInput, VertexCountChangeBetweenFramesNamesTheFile) {
  TempDir dir;
  write_mesh(dir / "a.ply", grid_frame(3, 0));
  MeshFrame more = grid_frame(3, 1);
  more.positions.emplace_back(9, 9, 9);
  write_mesh(dir / "b.ply", more);
  const auto source = make_file_frame_source({dir / "a.ply", dir / "b.ply"});
  const std::string error = error_of([&] { source->frame(1); });
  EXPECT_NE(error.find("b.ply"), std::string::npos) << error;
  EXPECT_NE(error.find("topology changed"), std::string::npos) << error;
}

TEST(FrameFilesBadInput, FaceChangeBetweenFramesNamesTheFace) {
  TempDir dir;
  write_mesh(dir / "a.ply", grid_frame(3, 0));
  MeshFrame flipped = grid_frame(3, 1);
  std::swap(flipped.faces[5][0], flipped.faces[5][1]);
  write_mesh(dir / "b.ply", flipped);
  const auto source = make_file_frame_source({dir / "a.ply", dir / "b.ply"});
  const std::string error = error_of([&] { source->frame(1); });
  EXPECT_NE(error.find("b.ply:face 5"), std::string::npos) << error;
}

TEST(SceneSequence, FrameFilesAreOneDeformableSelfCollidingObject) {
  TempDir dir;
  write_mesh(dir / "a.ply", grid_frame(3, 0));
  write_mesh(dir / "b.ply", grid_frame(3, 0.5));
  const SceneSequence sequence = scene_from_frame_files({dir / "a.ply", dir / "b.ply"}, 0.0);
  EXPECT_EQ(sequence.num_steps(), 1u);
  EXPECT_EQ(sequence.scene().objects().size(), 1u);
  EXPECT_TRUE(sequence.scene().object(0).self_collision);
  EXPECT_EQ(sequence.scene().thickness(), 0.0);
  EXPECT_EQ(sequence.frame(1)[8].z(), 0.5);
}

}  // namespace
}  // namespace ccd::datasets
