#include "core/error.hpp"
#include "datasets/frame_cache.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <cstring>

namespace ccd::datasets {
namespace {

TEST(FrameCache, WriteReadRoundTripIsBitExactAndKeyed) {
  testing::TempDir dir;
  const auto faces = testing::grid_faces(3);
  std::vector<std::vector<Vec3>> frames;
  {
    FrameCacheWriter writer(dir / "c.frames", "test v1 n=3", 9, faces);
    for (int k = 0; k < 4; ++k) {
      frames.push_back(testing::grid_positions(3, 0.1 * k));
      frames.back()[k] = Vec3(1.0 / 3.0, -1e-310, 1e300);
      writer.append(frames.back());
    }
    EXPECT_FALSE(std::filesystem::exists(dir / "c.frames")) << "visible before finish()";
    writer.finish();
  }
  EXPECT_FALSE(open_frame_cache(dir / "c.frames", "test v1 n=4").has_value());
  EXPECT_FALSE(open_frame_cache(dir / "absent.frames", "test v1 n=3").has_value());
  const auto source = open_frame_cache(dir / "c.frames", "test v1 n=3");
  ASSERT_TRUE(source.has_value());
  ASSERT_EQ((*source)->num_frames(), 4u);
  EXPECT_EQ((*source)->faces(), faces);
  for (std::size_t k = 0; k < 4; ++k) {
    const auto positions = (*source)->frame(k);
    EXPECT_EQ(std::memcmp(positions.data(), frames[k].data(), 9 * sizeof(Vec3)), 0) << "frame " << k;
  }
  EXPECT_EQ(frame_cache_key(dir / "c.frames"), "test v1 n=3");
}

TEST(FrameCache, AbandonedWriterLeavesNothing) {
  testing::TempDir dir;
  {
    FrameCacheWriter writer(dir / "c.frames", "k", 9, testing::grid_faces(3));
    writer.append(testing::grid_positions(3));
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(FrameCacheBadInput, TruncatedAndForeignFilesAreErrors) {
  testing::TempDir dir;
  {
    FrameCacheWriter writer(dir / "c.frames", "k", 9, testing::grid_faces(3));
    for (int k = 0; k < 3; ++k) writer.append(testing::grid_positions(3, k));
    writer.finish();
  }
  std::filesystem::resize_file(dir / "c.frames", std::filesystem::file_size(dir / "c.frames") - 8);
  try {
    open_frame_cache(dir / "c.frames", "k");
    FAIL() << "truncated cache accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("frame 2"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("truncated"), std::string::npos) << error.what();
  }
  testing::write_text(dir / "x.frames", "not a cache at all");
  EXPECT_THROW(open_frame_cache(dir / "x.frames", "k"), InputError);
}

}  // namespace
}  // namespace ccd::datasets
