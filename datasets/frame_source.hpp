#pragma once
/// @file
/// Where one object's frames come from: a list of mesh files, a frame cache, or (later) a generator.

#include "core/topology.hpp"
#include "core/vec.hpp"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace ccd::datasets {

/// A sequence of frames of one mesh with fixed topology. Frames are produced on demand, so a long sequence
/// never has to fit in memory.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual std::size_t num_vertices() const = 0;
  /// The topology shared by every frame (local vertex ids).
  virtual const std::vector<Face>& faces() const = 0;
  virtual std::size_t num_frames() const = 0;
  /// Positions of frame k < num_frames(). @throws InputError (file, element, reason) on bad data, including a
  /// vertex count or face list that differs from frame 0's.
  virtual std::vector<Vec3> frame(std::size_t k) const = 0;
  /// One line for messages and `ccdbench inspect`.
  virtual std::string describe() const = 0;
};

/// Frames read from mesh files (.ply/.obj), one file per frame, in the given order. The first file is read
/// at construction; every later one is checked against its vertex count and faces.
std::unique_ptr<FrameSource> make_file_frame_source(std::vector<std::filesystem::path> files);

/// A shape's motion track (a scene file's "track": {"centres": [...]}) as frames of one vertex and no faces: its
/// centre per frame. One centre holds the shape still over the whole sequence. `centres` must not be empty.
std::unique_ptr<FrameSource> make_track_frame_source(std::vector<Vec3> centres, std::string description);

/// The files of a frame sequence named by
///  - a directory: its *.ply/*.obj files whose names end in a frame number ("frame_0007.ply", "227.ply"),
///    sorted by that number; they must share one prefix and extension, with no gap in the numbers;
///  - a printf pattern with one integer conversion ("cloth/frame_%04d.ply"): every file of the pattern's folder
///    that the pattern names with some number, from 0 (or 1 when there is no frame 0), without a gap.
/// @throws InputError when nothing matches, numbers have a gap (frames 0 and 2 without 1), two files have the
///         same number ("frame_0001" and "frame_01"), a folder is named like a frame, or names mix prefixes.
std::vector<std::filesystem::path> expand_frame_files(const std::filesystem::path& directory_or_pattern);

}  // namespace ccd::datasets
