#pragma once
/// @file
/// The keys of the OpenCL backend, which every strategy with `backend=opencl` (full, apccd) takes alike.

#include "strategies/narrowphase/spec.hpp"

#include <cstddef>
#include <string>
#include <vector>

namespace ccd::strategies {

/// Sub-boxes a work item holds for one conservative query by default (private memory, 56 bytes each); a query that
/// needs more is handed on to a second pass that decides it from the start with the same code.
inline constexpr long kDefaultDeviceSubBoxes = 48;

struct BackendChoice {
  std::string backend = "cpu";
  /// device=INDEX|NAME-SUBSTRING; empty: the first GPU, else device 0.
  std::string device;
  /// Iterations a work item spends on one conservative query before giving it up to a second pass (0: never).
  long device_iterations = 200;
  /// Entries every device list starts with room for (0: sized from the scene). Lists grow as needed, so answers
  /// never depend on it; 1 makes every list grow and every stage run again (what tests/opencl checks).
  std::size_t list_start = 0;
  /// Sub-boxes a work item holds for one conservative query.
  long sub_boxes = kDefaultDeviceSubBoxes;

  bool opencl() const { return backend == "opencl"; }
  /// The backend's part of a resolved name: "" on the CPU; ":backend=opencl:device=NAME[:...]" otherwise, the
  /// memory keys only when not their defaults (so the names of earlier results stay).
  std::string resolved(const std::string& device_name, bool conservative) const;
};

/// backend, device, device_iterations, list_start, sub_boxes.
std::vector<narrowphase::KeySpec> backend_keys();

/// The backend keys of a strategy's reader. @throws std::invalid_argument for a device key without backend=opencl.
BackendChoice read_backend(const narrowphase::SpecReader& keys);

}  // namespace ccd::strategies
