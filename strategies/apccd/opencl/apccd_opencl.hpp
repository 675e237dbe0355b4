#pragma once
/// @file
/// `apccd:backend=opencl`: apccd's pipeline (cpu/apccd.cpp) with its heavy stages on an OpenCL device, testing the
/// same pairs as the CPU backend and so giving its collision set and TOIs bit for bit (same narrow phase).
///
/// What runs where. On the device: positions in each object's frame, the session's inflated refit and full self
/// traversal, dangling vertices and triangles, the leaves' enlargement and the partial traversal, the pending list,
/// the pairs across objects (fresh world-frame trees, or the session's trees swept by the centroids' translation),
/// the front end (fresh box overlap, then the distance heuristic, shared/separation.h), the expansion by the
/// assignment masks and the narrow phases (opencl/pipeline.hpp). On the host, in the CPU backend's own code
/// (apccd/session.hpp), every decision that sums over many elements: the centroids, the budgets and the session's
/// length at a session start (one pass over the vertices, whose budgets are then uploaded), and the session's end.
/// A device reduction would sum in another order, and a budget or an nf at its edge would flip; the host's sums
/// are the CPU backend's, in the same order. History (history=on) also runs on the host over the tested pairs.
///
/// The pending list is a hash table of 64-bit pair keys on the device (open addressing, linear probing, at most
/// half full) beside the list itself. Why not sorted pair arrays: merging a partial traversal's pairs into a sorted
/// list needs a device sort of the new pairs and a merge each frame; the table needs one atomic compare-and-swap
/// per new pair, and the front end reads the list in any order (its answer does not depend on it). The table is
/// built only when a session's first partial traversal finds pairs (at paper scale most sessions last one frame).
/// Devices need cl_khr_int64_base_atomics (PoCL and NVIDIA have it).

#include "strategies/apccd/session.hpp"
#include "strategies/backend.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/strategy.hpp"

#include <memory>

namespace ccd::strategies {

/// Chooses the device and checks it (fp64 with subnormals, 64-bit atomics); the context, the program and the
/// self-test come at init().
/// @throws std::invalid_argument for a narrow phase without a device form, or a device that lacks what the kernels
///         need, or when this build has no OpenCL.
std::unique_ptr<Strategy> make_apccd_opencl(const ApccdSettings& settings, std::unique_ptr<narrowphase::NarrowPhase> narrow_phase,
                                            const BackendChoice& backend);

}  // namespace ccd::strategies
