#include "datasets/scene_sequence.hpp"

#include "core/error.hpp"

namespace ccd::datasets {

SceneSequence::SceneSequence(Scene scene, std::vector<std::unique_ptr<FrameSource>> sources)
    : scene_(std::move(scene)), sources_(std::move(sources)) {
  if (sources_.size() != scene_.objects().size()) throw InputError({}, "scene", "one frame source per object needed");
  static_first_frames_.resize(sources_.size());
  std::size_t multi_frame_count = 0;
  std::string multi_frame_object;
  for (ObjectId id = 0; id < sources_.size(); ++id) {
    const SceneObject& object = scene_.object(id);
    const FrameSource& source = *sources_[id];
    if (source.num_vertices() != object.num_vertices || source.num_frames() == 0) {
      throw InputError({}, "object '" + object.name + "'", "frame source does not match the object (" + source.describe() + ")");
    }
    if (source.num_frames() == 1) continue;
    if (object.kind == ObjectKind::static_object) static_first_frames_[id] = source.frame(0);
    if (multi_frame_count != 0 && source.num_frames() != multi_frame_count) {
      throw InputError({}, "object '" + object.name + "'",
                       "has " + std::to_string(source.num_frames()) + " frames but object '" + multi_frame_object + "' has " +
                           std::to_string(multi_frame_count) + " (" + source.describe() + ")");
    }
    multi_frame_count = source.num_frames();
    multi_frame_object = object.name;
  }
  num_frames_ = multi_frame_count == 0 ? 1 : multi_frame_count;
}

std::vector<Vec3> SceneSequence::frame(std::size_t k) const {
  if (k >= num_frames_) throw std::out_of_range("SceneSequence::frame: frame " + std::to_string(k) + " of " + std::to_string(num_frames_));
  std::vector<Vec3> positions(scene_.topology().num_vertices());
  for (ObjectId id = 0; id < sources_.size(); ++id) {
    const SceneObject& object = scene_.object(id);
    const FrameSource& source = *sources_[id];
    const std::size_t local_frame = source.num_frames() == 1 ? 0 : k;
    std::vector<Vec3> local = source.frame(local_frame);
    if (object.kind == ObjectKind::static_object && local_frame != 0) {
      const std::vector<Vec3>& first = static_first_frames_[id];
      for (std::size_t i = 0; i < local.size(); ++i) {
        if (local[i] != first[i]) {
          throw InputError({}, "object '" + object.name + "', frame " + std::to_string(k) + ", vertex " + std::to_string(i),
                           "a static object must not move (" + source.describe() + ")");
        }
      }
    }
    std::copy(local.begin(), local.end(), positions.begin() + object.first_vertex);
  }
  return positions;
}

SceneSequence scene_from_frame_files(std::vector<std::filesystem::path> files, double thickness) {
  auto source = make_file_frame_source(std::move(files));
  ObjectDescription object{"mesh", ObjectKind::deformable, true, source->num_vertices(), source->faces()};
  std::vector<std::unique_ptr<FrameSource>> sources;
  sources.push_back(std::move(source));
  return SceneSequence(Scene({std::move(object)}, {}, thickness), std::move(sources));
}

}  // namespace ccd::datasets
