#pragma once
/// @file
/// What the harness compares (docs/DESIGN.md §3): a strategy is built once per scene and fed steps in order.

#include "core/collision_set.hpp"
#include "core/stage_timer.hpp"
#include "core/step.hpp"
#include "strategies/bvh/bvh.hpp"

#include <array>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace ccd::strategies {

/// Counts a strategy reports per step (beyond its stage times).
struct StepCounters {
  std::size_t candidate_triangle_pairs = 0;
  std::size_t elementary_tests = 0;
  /// Host memory the strategy keeps from step to step (hierarchies, trees, hash tables, apccd's pending pairs and
  /// history), in bytes.
  std::size_t kept_bytes = 0;
  /// apccd's history tables alone (part of kept_bytes; 0 for every other strategy), in bytes.
  std::size_t history_bytes = 0;
  /// Device buffers the strategy holds after the step (OpenCL; its lists grow, never shrink, so this is their peak
  /// so far), in bytes.
  std::size_t device_bytes = 0;
  /// Strategy-specific counts, e.g. apccd's dangling vertices.
  std::vector<std::pair<std::string, double>> extra;
};

/// Counters of `extra` that a reader shows (the run table's device budget column), by one name each: an OpenCL step's
/// memory budget in bytes, and the chunks it ran in within it.
inline constexpr const char* kDeviceBudgetCounter = "device_budget_bytes";
inline constexpr const char* kDeviceChunksCounter = "device_chunks";

/// The elementary pairs a step tested (audit mode), sorted: a miss not among them was culled before testing.
struct TestedPairs {
  std::vector<VertexFacePair> vertex_face;
  std::vector<EdgeEdgePair> edge_edge;
  /// Face-shape pairs that reached the narrow phase (past the cull).
  std::vector<FaceShapePair> face_shape = {};
};

/// Something a step could not answer without ending the run (a plugin's error, undecided or refused answer, a crash
/// or a hang of an isolated plugin): the harness counts it apart and writes it out to reproduce. With `rows`, an
/// elementary pair's (written out as a query file); without, the whole step's (written out as its frame pair).
struct Fault {
  std::string message;
  std::optional<std::array<Vec3, 8>> rows;
  bool vertex_face = true;
};

/// Faults a step keeps whole (the count covers every one): enough to reproduce and read, not a second answer set.
inline constexpr std::size_t kKeptFaults = 16;

struct StepResult {
  /// Normalized; TOIs from the narrow phase.
  CollisionSet collisions;
  StageTimes stages;
  StepCounters counters;
  /// Filled in audit mode only.
  std::optional<TestedPairs> tested;
  /// Strategies judged by triangle pairs only: the triangle pairs reported (a < b, sorted). `collisions` then
  /// holds every elementary pair of them (all_elementary_pairs).
  std::vector<bvh::TrianglePair> triangle_pairs;
  /// How many faults the step had, and the first kKeptFaults of them (in a fixed order).
  std::size_t fault_count = 0;
  std::vector<Fault> faults;
};

/// How answers are judged (docs/DESIGN.md §3; each registry entry says which, registry.hpp). By triangle pairs: a truth pair counts as found when a reported triangle
/// pair contains both its primitives, and a false alarm is a reported triangle pair containing no truth pair.
enum class Judging { elementary_pairs, triangle_pairs };

class Strategy {
 public:
  virtual ~Strategy() = default;
  /// The resolved spec, every default filled in: the strategy's name in every result.
  virtual std::string name() const = 0;
  /// Throws std::invalid_argument when the strategy cannot run `scene` (fcl at δ > 0), before any work; init
  /// checks it too.
  virtual void check_scene(const Scene&) const {}
  /// The scene's label in results, told before init: a strategy that reads answers made elsewhere (answers:DIR)
  /// finds the scene's files by it; the others ignore it.
  virtual void name_scene(const std::string& /*label*/) {}
  /// Readies what does not depend on a scene, for strategies made after this one is gone: a device's context (kept
  /// by the OpenCL backend for the next strategy on that device; opencl::lease_context). What an MPI rank does while
  /// rank 0 plans. Nothing for most strategies.
  virtual void prepare() {}
  /// Prepares for `scene`; `first_frame` holds frame 0's global positions.
  virtual void init(const Scene& scene, std::span<const Vec3> first_frame) = 0;
  /// One step, in order. With `audit`, also returns the elementary pairs tested (outside the timed stages).
  virtual StepResult step(const StepView& step, bool audit) = 0;
  /// What a result of this strategy depends on beyond the build (docs/DESIGN.md §5 provenance), as name-value pairs: the
  /// OpenCL backend's platform, device and driver. Empty for a strategy that runs on the host alone.
  virtual std::vector<std::pair<std::string, std::string>> provenance() const { return {}; }
};

}  // namespace ccd::strategies
