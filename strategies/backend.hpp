#pragma once
/// @file
/// The keys of the OpenCL backend, which every strategy with `backend=opencl` (full, apccd) takes alike.

#include "strategies/narrowphase/spec.hpp"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ccd::strategies {

/// Sub-boxes a work item holds for one conservative query by default (private memory, 56 bytes each); a query that
/// needs more is handed on to the deep pass, which decides it from the start with the same code and kDeepSubBoxFactor
/// times the sub-boxes in device memory (opencl/pipeline.hpp).
inline constexpr long kDefaultDeviceSubBoxes = 48;

/// The device memory a step may use (memory=): a share of the device's global memory ("75%", the default) or bytes
/// ("2G", "512M", binary suffixes K, M, G, T, or a plain count). A step whose lists would not fit runs in chunks
/// (full) or is refused naming the limit (apccd); the answers are the same under any budget.
struct MemoryBudget {
  double percent = 75;  // of the device's global memory, when bytes is 0
  std::uint64_t bytes = 0;
  /// The budget on a device with `device_memory` bytes of global memory.
  std::uint64_t on_device(std::uint64_t device_memory) const;
  /// As the key reads back ("75%", "2147483648").
  std::string text() const;
  bool is_default() const { return bytes == 0 && percent == 75; }
};

/// Reads memory=TEXT. @throws std::invalid_argument naming what is wrong.
MemoryBudget parse_memory_budget(const std::string& text);

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
  MemoryBudget memory;

  bool opencl() const { return backend == "opencl"; }
  /// The backend's part of a resolved name: "" on the CPU; ":backend=opencl:device=NAME[:...]" otherwise, the
  /// memory keys only when not their defaults (so the names of earlier results stay).
  std::string resolved(const std::string& device_name, bool conservative) const;
};

/// backend, device, device_iterations, list_start, sub_boxes, memory.
std::vector<narrowphase::KeySpec> backend_keys();

/// The backend keys of a strategy's reader. @throws std::invalid_argument for a device key without backend=opencl.
BackendChoice read_backend(const narrowphase::SpecReader& keys);

/// This process's turn among the processes of one node that share its OpenCL devices: an MPI job's node-local rank
/// and how many ranks the node runs (0 of 1 otherwise). A spec that names no device takes the node's GPUs (its
/// devices, where it has no GPU) in turn by it, so that the ranks of a node use every GPU (docs/mpi.md).
struct DeviceTurn {
  int turn = 0;
  int of = 1;
};

/// Set once by the harness when MPI has started, before any strategy is made.
void set_device_turn(DeviceTurn turn);
DeviceTurn device_turn();

}  // namespace ccd::strategies
