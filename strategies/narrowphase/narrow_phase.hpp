#pragma once
/// @file
/// The elementary tests every strategy shares (docs/DESIGN.md §3): one vertex-face and one edge-edge call on a pair
/// with linear motion over the step, thickness δ >= 0. Variants differ in precision and in what they guarantee.

#include "core/vec.hpp"

#include <array>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace ccd::narrowphase {

/// Rows in the query files' order: VF v_t0, f0_t0, f1_t0, f2_t0, v_t1, f0_t1, f1_t1, f2_t1;
/// EE ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1.
using PairRows = std::array<Vec3, 8>;

/// What a test answers, with what a user needs to judge it (docs/STYLE.md "Shape").
struct NarrowPhaseResult {
  bool collides = false;
  /// Earliest time of contact in [0, 1] when collides (conservative variants: never later than the true one);
  /// NaN otherwise.
  double toi = std::numeric_limits<double>::quiet_NaN();
  /// The iteration cap stopped the test; a conservative variant then answers "collides".
  bool hit_iteration_cap = false;
  /// The distance tolerance the answer was reached with (0 when exact up to rounding).
  double achieved_tolerance = 0.0;
  /// Not empty when the method gave no answer (a plugin's "undecided" or error, or an answer ccdbench refused: a
  /// TOI out of [0, 1]): why. `collides` then says how it counts (a plugin's `errors` key); it is counted apart too.
  std::string fault;
};

/// How the OpenCL kernels run a narrow phase: the same shared text (shared/*.h) compiled for the device, with the
/// settings the host's instance has, so that both give the same answers bit for bit.
struct DeviceForm {
  enum class Kernel { cubic64, conservative };
  Kernel kernel = Kernel::cubic64;
  /// cubic64: eta; conservative: tolerance (fractions of the pair's bounding-box diagonal).
  double accuracy = 0;
  /// conservative: the TOI's tolerance in time (a fraction of the step).
  double toi_tolerance = 0;
  /// conservative: sub-boxes examined before giving up.
  long max_iterations = 0;
};

class NarrowPhase {
 public:
  virtual ~NarrowPhase() = default;
  /// The resolved spec: name and every parameter with its value, e.g. "cubic64:eta=1e-06".
  virtual std::string name() const = 0;
  /// Whether the variant promises no false negatives on any input.
  virtual bool conservative() const = 0;
  virtual NarrowPhaseResult vertex_face(const PairRows& rows, double thickness) const = 0;
  virtual NarrowPhaseResult edge_edge(const PairRows& rows, double thickness) const = 0;
  /// The form the OpenCL backend runs, or nullopt when it has no kernel for this narrow phase.
  virtual std::optional<DeviceForm> device_form() const { return std::nullopt; }
  /// Whether it may be called from several threads at once. One that may not (a plugin without
  /// CCDBENCH_THREAD_SAFE) makes its strategy run on one thread (make_strategy), said in every record.
  virtual bool thread_safe() const { return true; }
  /// What a result of it depends on beyond its name and the build (a plugin's code and where it ran), as name-value
  /// pairs that its strategy's records carry (make_strategy adds them to the strategy's provenance).
  virtual std::vector<std::pair<std::string, std::string>> provenance() const { return {}; }

  /// One pair of a batch: its rows (alive for the call), whether it is vertex-face, and δ.
  struct BatchPair {
    const PairRows* rows;
    bool vertex_face;
    double thickness;
  };
  /// Whether answering many pairs in one call costs much less than one call each (an isolated plugin: one round
  /// trip to its process per batch instead of per pair): callers then gather pairs and call `answer_batch`.
  virtual bool prefers_batches() const { return false; }
  /// With prefers_batches: how many pairs of one kind a caller gathers into one call (a step's pairs are asked in
  /// calls of at most this many).
  virtual std::size_t preferred_batch() const { return 4096; }
  /// The answers of `pairs`, in order, into `results` (as large): the same answers as one call each.
  virtual void answer_batch(std::span<const BatchPair> pairs, std::span<NarrowPhaseResult> results) const {
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      results[i] = pairs[i].vertex_face ? vertex_face(*pairs[i].rows, pairs[i].thickness) : edge_edge(*pairs[i].rows, pairs[i].thickness);
    }
  }
};

}  // namespace ccd::narrowphase
