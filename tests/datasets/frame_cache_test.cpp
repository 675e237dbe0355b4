#include "datasets/frame_cache.hpp"
#include "core/error.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <fstream>

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
  // Cut into the last frame (the 32-byte checksum and 8 bytes of frame 2).
  std::filesystem::resize_file(dir / "c.frames", std::filesystem::file_size(dir / "c.frames") - 40);
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

// A flipped bit anywhere (a position, a face, the frame count, the checksum) makes the cache an error, never used.
TEST(FrameCacheBadInput, EveryFlippedBitIsDetected) {
  testing::TempDir dir;
  {
    FrameCacheWriter writer(dir / "c.frames", "k", 4, testing::grid_faces(2));
    for (int k = 0; k < 2; ++k) writer.append(testing::grid_positions(2, k));
    writer.finish();
  }
  ASSERT_TRUE(open_frame_cache(dir / "c.frames", "k"));
  std::ifstream in(dir / "c.frames", std::ios::binary);
  const std::string original((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  for (std::size_t byte = 0; byte < original.size(); ++byte) {
    std::string flipped = original;
    flipped[byte] = static_cast<char>(flipped[byte] ^ 0x10);
    testing::write_text(dir / "c.frames", flipped);
    EXPECT_THROW(open_frame_cache(dir / "c.frames"), InputError) << "byte " << byte;
  }
}

// A corrupt count must not wrap around 2^64 into a small expected size and then be allocated.
TEST(FrameCacheBadInput, CountsThatTheFileCannotHoldAreRefusedBeforeAllocating) {
  testing::TempDir dir;
  {
    FrameCacheWriter writer(dir / "c.frames", "k", 9, testing::grid_faces(3));
    writer.append(testing::grid_positions(3));
    writer.finish();
  }
  std::fstream file(dir / "c.frames", std::ios::in | std::ios::out | std::ios::binary);
  const std::streamoff faces_count = 8 + 4 + 4 + 8 + 1 + 8;     // magic, version, reserved, key length, key, vertices
  const std::uint64_t wrapping = (std::uint64_t{1} << 62) + 1;  // 12 * wrapping wraps to 12
  file.seekp(faces_count);
  file.write(reinterpret_cast<const char*>(&wrapping), sizeof wrapping);
  file.close();
  const std::string error = testing::error_message<InputError>([&] { open_frame_cache(dir / "c.frames", "k"); });
  EXPECT_NE(error.find("c.frames:header: corrupt counts"), std::string::npos) << error;
}

}  // namespace
}  // namespace ccd::datasets
