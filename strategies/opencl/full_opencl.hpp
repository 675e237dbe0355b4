#pragma once
/// @file
/// `full:backend=opencl`: the full-traversal strategy with every stage on an OpenCL device (kernels/full.cl), giving
/// the CPU `full`'s collision set and TOIs bit for bit for the same narrow phase (conservative or cubic64).
///
/// The hierarchy: each object's tree is built once on the host, exactly as the CPU's (a median split), and refitted
/// on the device every step, level by level. Cloth keeps its topology, so a refit tree stays as valid as the CPU's;
/// and the candidate set does not depend on the tree at all (it is every face pair whose leaf boxes overlap), so
/// the choice is about speed only. An LBVH rebuilt per step from Morton codes would need a radix sort on the
/// device each step for no change in the answer; a refit is a few level launches. Traversal is one work item per
/// face against a whole tree, which needs no synchronisation and fills the GPU at cloth sizes.

#include "strategies/backend.hpp"
#include "strategies/narrowphase/entry.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

#include <cstdint>
#include <map>
#include <memory>
#include <string>

namespace ccd::strategies {

/// A device as `ccdbench devices` lists it (no OpenCL types, so the harness needs no OpenCL header).
struct OpenClDeviceSummary {
  std::size_t index = 0;
  std::string platform, name, version, driver;
  bool gpu = false;
  unsigned compute_units = 0;
  std::uint64_t global_memory = 0;
  bool fp64 = false;
  bool fp64_denormals = false;
  /// cl_khr_int64_base_atomics, which apccd:backend=opencl's pending list needs.
  bool int64_atomics = false;
  /// Whether full:backend=opencl accepts it (fp64 that keeps subnormals); else why not.
  std::string refused_because;
};

/// Every OpenCL device, in device=INDEX order. @throws std::invalid_argument when this build has no OpenCL.
std::vector<OpenClDeviceSummary> opencl_devices();

/// `strategy`:backend=opencl checked as its factory checks it, without making anything (registry.hpp's validate and
/// resolved_name): the narrow phase has a device form, and the device the keys choose is there with (denormal-keeping)
/// fp64, and 64-bit atomics where `int64_atomics`. @return the device's name, which resolved names carry.
/// @throws std::invalid_argument as make_full_opencl does.
std::string opencl_device_name(const std::string& strategy, const BackendChoice& backend, const narrowphase::ResolvedNarrowPhase& narrow,
                               bool int64_atomics);

/// The backend's part of `strategy`'s resolved name, which the entries of both strategies with an OpenCL backend
/// (full, apccd) check and name it by: "" on the CPU; with backend=opencl, the device checked (opencl_device_name)
/// and BackendChoice::resolved. @throws std::invalid_argument as opencl_device_name does.
inline std::string resolved_backend(const std::string& strategy, const BackendChoice& backend, const narrowphase::ResolvedNarrowPhase& narrow,
                                    bool int64_atomics) {
  return backend.opencl() ? backend.resolved(opencl_device_name(strategy, backend, narrow, int64_atomics), narrow.conservative) : "";
}

/// Chooses the device (listing them) and checks it has what the kernels need, so a bad device is refused when the
/// run is planned. The context, the program and the device's arithmetic self-test come at init().
/// @throws std::invalid_argument for a narrow phase without a device form, a missing device, or a device without
///         (denormal-keeping) fp64, or when this build has no OpenCL.
/// `separation_filter`: full's filter=on (full_traversal.cpp), the same filter on the device.
std::unique_ptr<Strategy> make_full_opencl(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase, const BackendChoice& backend,
                                           bool separation_filter = false);

}  // namespace ccd::strategies
