#include "harness/run/scene_store.hpp"

#include "core/error.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <exception>
#include <utility>

namespace ccd::harness {

namespace {

/// Frames 0..count-1 of `sequence`, read in parallel: one by one, a paper scene's 100 frames took about as long as its
/// cell on a GPU, and under MPI rank 0 reads every scene before any rank starts. A bad frame is reported as read in
/// order: the first one's error.
std::vector<std::vector<Vec3>> read_frames(const datasets::SceneSequence& sequence, std::size_t count) {
  std::vector<std::vector<Vec3>> frames(count);
  std::vector<std::exception_ptr> errors(count);
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t k) {
    try {
      frames[k] = sequence.frame(k);
    } catch (...) {
      errors[k] = std::current_exception();
    }
  });
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
  return frames;
}

}  // namespace

std::vector<SceneVariant> scene_variants(const RunOptions& options) {
  const std::vector<std::optional<double>> thicknesses =
      options.thicknesses.empty() ? std::vector<std::optional<double>>{std::nullopt} : options.thicknesses;
  std::vector<SceneVariant> variants;
  for (const SceneSource& source : options.scenes) {
    for (const std::optional<double>& thickness : thicknesses) variants.push_back({&source, thickness});
  }
  return variants;
}

SceneData& SceneStore::get(std::size_t index) {
  for (auto it = loaded_.begin(); it != loaded_.end(); ++it) {
    if (it->first != index) continue;
    loaded_.splice(loaded_.begin(), loaded_, it);
    return *loaded_.front().second;
  }
  const auto sibling =
      std::find_if(loaded_.begin(), loaded_.end(), [&](const auto& held) { return variants_[held.first].source == variants_.at(index).source; });
  loaded_.emplace_front(index, load(index, sibling != loaded_.end() ? sibling->second.get() : nullptr));
  if (loaded_.size() > kKept) loaded_.pop_back();
  return *loaded_.front().second;
}

std::unique_ptr<SceneData> SceneStore::load(std::size_t index, SceneData* sibling, bool take) const {
  const SceneVariant& variant = variants_.at(index);
  const SceneSource& source = *variant.source;
  auto data = std::make_unique<SceneData>(SceneData{source.label, source.load(), {}, {}, {}, 0, variant.thickness ? "command line" : "scene"});
  if (variant.thickness) data->sequence.set_thickness(*variant.thickness);
  data->steps = data->sequence.num_steps();
  if (options_.max_steps > 0) data->steps = std::min(data->steps, options_.max_steps);
  if (data->steps == 0) throw InputError(source.label, {}, "the scene has no steps (one frame)");
  // The same scene at another δ has the same frames: copied (or moved), not read and checked again (a paper scene's
  // 100 PLY frames take longer to read than its cell takes on a GPU).
  // (Checked against the scene as loaded now: one whose files changed between the two loads is read again.)
  const std::size_t vertices = data->sequence.scene().topology().num_vertices();
  if (sibling != nullptr && sibling->frames.size() == data->steps + 1 && sibling->frames[0].size() == vertices) {
    if (take) {
      data->frames = std::move(sibling->frames);
    } else {
      data->frames = sibling->frames;
    }
  } else {
    data->frames = read_frames(data->sequence, data->steps + 1);
  }
  data->truth.resize(data->steps);
  data->has_truth.assign(data->steps, false);
  return data;
}

}  // namespace ccd::harness
