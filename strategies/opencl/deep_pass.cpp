// The deep pass of the conservative narrow phase on the device: the queries that overflowed a work item's private
// sub-boxes, run again with kDeepSubBoxFactor times as many in device memory (the deep build of the kernels,
// -DCCD_DEEP_PASS). Before it the host decided them all, and a step of the paper's pile at δ = 0 spent a third of
// its time there on 64 cores (reports/gpus).
#include "strategies/opencl/pipeline.hpp"

#include <algorithm>
#include <chrono>

namespace ccd::opencl {

std::size_t DevicePipeline::deep_sub_boxes() const { return kDeepSubBoxFactor * static_cast<std::size_t>(backend_.sub_boxes); }

std::size_t DevicePipeline::deep_batch() const {
  std::size_t room = std::min<std::size_t>(kDeepStoreMaxBytes, device_.max_allocation);
  if (pair_limit_ != 0) room = std::min(room, pair_limit_ * kDeepStoreBytesPerElementary);
  if (own_bytes_limit_) {
    const std::size_t held = bytes() - deep_store_.bytes(), limit = own_bytes_limit_();
    room = held < limit ? std::min(room, limit - held) : 0;
  }
  // Each query's sub-boxes, and its entry in the retry buffers (pair, status, TOI) should they grow for it.
  return room / (deep_sub_boxes() * kSubBoxBytes + sizeof(cl_uint4) + 1 + sizeof(double));
}

void DevicePipeline::launch_deep(const Buffer& pairs, std::size_t count, const Buffer& x0, const Buffer& x1, StageEvents& events) {
  Context& context = *context_;
  cl_kernel kernel = context.kernel("narrow_conservative_deep", Context::Build::deep);
  const std::size_t capacity = deep_sub_boxes();
  const cl_double tolerance = narrow_phase_.form.accuracy, toi_tolerance = narrow_phase_.form.toi_tolerance;
  const cl_long max_iterations = narrow_phase_.form.max_iterations;
  set_arguments(kernel, static_cast<cl_uint>(count), pairs.get(), faces_.get(), x0.get(), x1.get(), scene_->thickness(), tolerance, toi_tolerance,
                max_iterations, deep_store_.get(), static_cast<cl_uint>(capacity), retry_status_.get(), retry_toi_.get());
  launch(context, kernel, count, narrow_group(kernel), events.add("narrow phase"));
}

void DevicePipeline::deep_pass(StageEvents& events, const std::vector<std::size_t>& which, const std::vector<cl_uint4>& pairs,
                               std::vector<cl_uchar>& status, std::vector<double>& toi, const Buffer& x0, const Buffer& x1, Decided& into) {
  const std::size_t batch = deep_batch();
  if (which.empty() || batch == 0) return;
  const std::size_t query_bytes = deep_sub_boxes() * kSubBoxBytes;
  deep_store_.reserve(*context_, std::min(batch, which.size()) * query_bytes, batch * query_bytes);
  // Its wall time (each batch ends with a blocking download), as the later passes' (pipeline.cpp, decide).
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t first = 0; first < which.size(); first += batch) {
    const std::size_t end = std::min(which.size(), first + batch);
    const std::vector<std::size_t> part(which.begin() + static_cast<std::ptrdiff_t>(first), which.begin() + static_cast<std::ptrdiff_t>(end));
    device_pass(events, part, 0, pairs, status, toi, x0, x1, true);
    into.deep_pass += part.size();
    for (const std::size_t i : part) into.deep_colliding += status[i] == 1;
  }
  into.deep_pass_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace ccd::opencl
