#pragma once
/// @file
/// The scenes of a run as a rank loads them: each scene at each of the run's thicknesses (a variant), its frames read
/// in parallel, and the few this rank holds at once.

#include "harness/run/cells.hpp"
#include "harness/run/options.hpp"

#include <cstddef>
#include <list>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace ccd::harness {

/// A scene at one of the run's thicknesses (nullopt: its own).
struct SceneVariant {
  const SceneSource* source;
  std::optional<double> thickness;
};

/// Every scene at every thickness, scene by scene (a scene's variants next to each other).
std::vector<SceneVariant> scene_variants(const RunOptions& options);

/// The scenes this rank has loaded, by index in the run's variants: loaded when a work item first needs one, and
/// at most kKept at once (a rank may alternate between scenes when the work queue hands out cells of several).
class SceneStore {
 public:
  SceneStore(const RunOptions& options, const std::vector<SceneVariant>& variants) : options_(options), variants_(variants) {}

  /// Variant `index`, loaded now unless held.
  SceneData& get(std::size_t index);
  /// Variant `index` loaded, held by the caller (not this store): its frames read, or taken from `sibling` (the
  /// same scene at another δ, as loaded just before) when its frames fit: copied, or moved where `take` (the caller
  /// needs them no more). Safe to call from several threads.
  std::unique_ptr<SceneData> load(std::size_t index, SceneData* sibling, bool take = false) const;

  /// The scene a work item used last (the one a cell in progress runs on), or nullptr.
  const SceneData* last() const { return loaded_.empty() ? nullptr : loaded_.front().second.get(); }

 private:
  static constexpr std::size_t kKept = 2;
  const RunOptions& options_;
  const std::vector<SceneVariant>& variants_;
  std::list<std::pair<std::size_t, std::unique_ptr<SceneData>>> loaded_;
};

}  // namespace ccd::harness
