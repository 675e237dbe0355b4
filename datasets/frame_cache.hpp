#pragma once
/// @file
/// A binary frame cache, so that a generated or parsed sequence is produced once and then read back fast.
///
/// Layout (all little-endian): "CCDBFRM1", u32 version (2), u32 reserved, u64 key length, the key bytes,
/// u64 vertices, u64 faces, u64 frames, faces as 3 u32 each, then each frame's positions as 3 f64 per vertex, and
/// a 32-hex-digit checksum (ContentHash of everything before it but the frame count, then the count). The checksum
/// is verified when a cache is opened; a corrupt cache is an InputError, never used.
/// The key is any text that identifies what was cached (a generator's name and parameters); a reader that
/// expects another key treats the cache as absent.

#include "datasets/frame_source.hpp"

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace ccd::datasets {

/// Writes a cache frame by frame (memory stays one frame), visible under `path` only after finish().
class FrameCacheWriter {
 public:
  FrameCacheWriter(const std::filesystem::path& path, const std::string& key, std::size_t num_vertices, const std::vector<Face>& faces);
  ~FrameCacheWriter();
  FrameCacheWriter(const FrameCacheWriter&) = delete;
  FrameCacheWriter& operator=(const FrameCacheWriter&) = delete;

  /// Appends one frame; `positions` must have num_vertices entries.
  void append(std::span<const Vec3> positions);
  /// Writes the frame count and renames the file into place.
  void finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Opens the cache at `path` as a frame source when it exists and was written with `expected_key`;
/// nullopt when it is absent or holds another key.
/// @throws InputError when the file exists but is not a valid cache (bad magic, version, truncated).
std::optional<std::unique_ptr<FrameSource>> open_frame_cache(const std::filesystem::path& path, const std::string& expected_key);

/// Opens a cache whatever its key (for scene files that name a cache, and for inspect).
/// @throws InputError when absent or invalid.
std::unique_ptr<FrameSource> open_frame_cache(const std::filesystem::path& path);

/// The key stored in a cache file. @throws InputError when it is not a valid cache.
std::string frame_cache_key(const std::filesystem::path& path);

}  // namespace ccd::datasets
