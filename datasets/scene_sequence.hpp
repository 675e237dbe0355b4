#pragma once
/// @file
/// A scene together with where its frames come from: what every command that runs steps consumes.

#include "core/scene.hpp"
#include "datasets/frame_source.hpp"

#include <memory>
#include <vector>

namespace ccd::datasets {

/// One frame source per scene object. Objects whose source has a single frame are held still over the whole
/// sequence (a static obstacle given once); all others must have the same frame count.
class SceneSequence {
 public:
  /// @throws InputError when frame counts disagree, or a source's topology does not match its object.
  SceneSequence(Scene scene, std::vector<std::unique_ptr<FrameSource>> sources);

  const Scene& scene() const { return scene_; }
  std::size_t num_frames() const { return num_frames_; }
  /// Steps are frame k -> k + 1.
  std::size_t num_steps() const { return num_frames_ == 0 ? 0 : num_frames_ - 1; }
  const FrameSource& source(ObjectId object) const { return *sources_[object]; }

  /// Global positions of frame k (all objects, scene numbering).
  /// @throws InputError on bad frame data, and when a static object's positions differ from its frame 0.
  std::vector<Vec3> frame(std::size_t k) const;

  /// The same sequence with another thickness.
  void set_thickness(double thickness) { scene_ = scene_.with_thickness(thickness); }

 private:
  Scene scene_;
  std::vector<std::unique_ptr<FrameSource>> sources_;
  std::size_t num_frames_ = 0;
  /// Frame 0 of each static object given as several frames, to check that it never moves; empty otherwise.
  std::vector<std::vector<Vec3>> static_first_frames_;
};

/// Two or more mesh files as one deformable object named "mesh" with self-collision on: what
/// `--frames A.ply B.ply` means (docs/DESIGN.md §1).
SceneSequence scene_from_frame_files(std::vector<std::filesystem::path> files, double thickness);

}  // namespace ccd::datasets
