// The memory budget of the OpenCL backend (memory=): how much of it a step's lists get, and the bound every
// per-pair buffer of the narrow phase keeps to. The chunks themselves are the strategies' (full_opencl.cpp).
#include "strategies/opencl/pipeline.hpp"

#include <algorithm>
#include <stdexcept>

namespace ccd::opencl {

void DevicePipeline::reserve_pairs(Buffer& buffer, std::size_t entries, std::size_t entry_bytes) {
  const std::size_t room = pair_limit_ != 0 ? pair_limit_ * entry_bytes : static_cast<std::size_t>(-1);
  buffer.reserve(*context_, std::max<std::size_t>(entries, 1) * entry_bytes, room);
}

std::uint64_t DevicePipeline::budget_bytes() const {
  const strategies::MemoryBudget& memory = backend_.memory;
  if (memory.bytes > device_.global_memory) {
    throw std::invalid_argument(label_ + ": memory=" + memory.text() + " is more than device " + std::to_string(device_.index) + " (" + device_.name +
                                ") has: " + std::to_string(device_.global_memory) + " bytes");
  }
  return memory.on_device(device_.global_memory);
}

ChunkRoom DevicePipeline::plan_room(std::uint64_t fixed, std::size_t least_candidates) {
  ChunkRoom room;
  room.fixed = fixed;
  const strategies::MemoryBudget& memory = backend_.memory;
  room.budget = budget_bytes();
  const std::uint64_t minimum = fixed + least_candidates * kBytesPerCandidate + kMinimumChunkElementary * kBytesPerElementary;
  if (room.budget < minimum) {
    throw std::invalid_argument(label_ + ": memory=" + memory.text() + " (" + std::to_string(room.budget) +
                                " bytes) is below what this scene needs at least: " + std::to_string(minimum) + " bytes (" + std::to_string(fixed) +
                                " for its topology, hierarchies, positions and queries, and the room of one chunk with " +
                                std::to_string(least_candidates) + " candidate pairs); give memory=" + std::to_string(minimum) + " or more");
  }
  // An eighth of the lists' room for candidates (at least one query's), the rest for elementary pairs; each list
  // within what the device allocates at once and what a kernel indexes in 32 bits.
  const std::uint64_t lists = room.budget - fixed;
  const std::uint64_t largest = device_.max_allocation;
  room.candidates = static_cast<std::size_t>(std::min<std::uint64_t>(
      {std::max<std::uint64_t>(least_candidates, lists / 8 / kBytesPerCandidate), largest / kBytesPerCandidate, kMaxCandidatesPerStep}));
  room.elementary = static_cast<std::size_t>(
      std::min<std::uint64_t>({(lists - room.candidates * kBytesPerCandidate) / kBytesPerElementary, largest / sizeof(cl_uint4), 0xFFFFFFFFull}));
  pair_limit_ = room.elementary;
  out_.set_limit(room.elementary, sizeof(cl_uint4));
  // Planned again with less room for pairs: what holds more is given back, to be reserved within the new room.
  for (Buffer* buffer : {&keep_, &status_, &out_status_, &retry_status_}) buffer->release_above(room.elementary);
  for (Buffer* buffer : {&toi_, &out_toi_, &retry_toi_}) buffer->release_above(room.elementary * sizeof(double));
  retry_pairs_.release_above(room.elementary * sizeof(cl_uint4));
  deep_store_.release_above(room.elementary * kDeepStoreBytesPerElementary);
  return room;
}

}  // namespace ccd::opencl
