#include "strategies/opencl/full_opencl.hpp"

#include "ccd/config.hpp"
#include "strategies/face_shape.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"

#if CCDBENCH_WITH_OPENCL
#include "strategies/opencl/pipeline.hpp"
#endif

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <stdexcept>

namespace ccd::strategies {

#if CCDBENCH_WITH_OPENCL
namespace {

using opencl::Buffer;
using opencl::upload;

class FullOpenCl final : public Strategy {
 public:
  FullOpenCl(opencl::NarrowPhaseChoice narrow_phase, opencl::DeviceInfo device, const BackendChoice& backend, bool separation_filter)
      : pipeline_(std::move(narrow_phase), std::move(device), backend, "full:backend=opencl"), separation_filter_(separation_filter) {}

  std::vector<std::pair<std::string, std::string>> provenance() const override { return pipeline_.provenance(); }

  std::string name() const override {
    const opencl::NarrowPhaseChoice& narrow = pipeline_.narrow_phase();
    return "full+" + narrow.host->name() + (separation_filter_ ? ":filter=on" : "") +
           pipeline_.backend().resolved(pipeline_.device().name, narrow.conservative());
  }

  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    pipeline_.init(scene, first_frame);
    pipeline_.make_queries(queries_, true, true, false);
    opencl::Context& context = pipeline_.context();
    // Static objects are fitted once, here, over frame 0 (as the CPU does): every leaf and every level now.
    node_boxes_.reserve(context, std::max<std::size_t>(pipeline_.node_count(), 1) * 6 * sizeof(double));
    positions_.reset(context, first_frame);
    pipeline_.refit(pipeline_.all_nodes(), positions_.x0(), positions_.x1(), scene.thickness() / 2, nullptr, node_boxes_, nullptr);
    context.finish();
  }

  StepResult step(const StepView& step, bool audit) override {
    const auto started = std::chrono::steady_clock::now();
    StepResult result;
    opencl::StageEvents events;
    opencl::Context& context = pipeline_.context();
    positions_.begin(context, step, events);
    const Buffer& x0 = positions_.x0();
    const Buffer& x1 = positions_.x1();
    pipeline_.vertex_boxes(x0, x1, events);
    pipeline_.refit(pipeline_.moving_nodes(), x0, x1, pipeline_.scene().thickness() / 2, nullptr, node_boxes_, &events);
    const std::size_t candidates = pipeline_.traverse(queries_, node_boxes_, nullptr, candidates_, events, "traversal");
    const std::size_t elementary = pipeline_.expand(candidates_.buffer, candidates, elementary_, events);
    const opencl::DeviceList* tested = &elementary_;
    if (separation_filter_) {
      pipeline_.filter(elementary_.buffer, elementary, x0, x1, kept_, events);
      tested = &kept_;
    }
    const std::size_t tests = separation_filter_ ? kept_.count : elementary;
    pipeline_.back_end(tested->buffer, tests, step, x0, x1, result, events);
    for (const auto& [stage, milliseconds] : events.collect()) result.stages.add(stage, milliseconds);
    result.counters.extra.emplace_back("device_span_ms", events.span_milliseconds());
    result.counters.extra.emplace_back("device_idle_ms", events.idle_milliseconds());
    if (audit) result.tested = pipeline_.tested_pairs(tested->buffer, tests);
    if (separation_filter_) result.counters.extra.emplace_back("distance_filtered", static_cast<double>(elementary - tests));
    positions_.finish(step);
    // Face-shape pairs on the host, with the host's narrow phase (face_shape.hpp), as the CPU backend does.
    run_face_shape_stage(result, pipeline_.scene(), step, *pipeline_.narrow_phase().host, audit);
    result.counters.candidate_triangle_pairs = candidates;
    result.counters.elementary_tests = tests;
    result.counters.device_bytes = pipeline_.bytes() + positions_.bytes() + node_boxes_.bytes() + queries_.bytes() + candidates_.buffer.bytes() +
                                   elementary_.buffer.bytes() + kept_.buffer.bytes();
    opencl::add_launch_and_wait(result, started);
    return result;
  }

 private:
  opencl::DevicePipeline pipeline_;
  bool separation_filter_ = false;
  opencl::Queries queries_;
  opencl::DevicePositions positions_;
  Buffer node_boxes_;
  opencl::DeviceList candidates_, elementary_, kept_;
};

}  // namespace

std::vector<OpenClDeviceSummary> opencl_devices() {
  std::vector<OpenClDeviceSummary> summaries;
  for (const opencl::DeviceInfo& d : opencl::list_devices()) {
    OpenClDeviceSummary s{d.index,         d.platform,      d.name, d.version,        d.driver,        d.is_gpu,
                          d.compute_units, d.global_memory, d.fp64, d.fp64_denormals, d.int64_atomics, ""};
    try {
      opencl::require_double_precision(d);
    } catch (const std::invalid_argument& refusal) {
      s.refused_because = refusal.what();
    }
    summaries.push_back(std::move(s));
  }
  return summaries;
}

std::string opencl_device_name(const std::string& strategy, const BackendChoice& backend, const narrowphase::ResolvedNarrowPhase& narrow,
                               bool int64_atomics) {
  if (!narrow.on_device) opencl::refuse_host_narrow_phase(strategy, narrow.name);
  return opencl::choose_checked_device(strategy, backend.device, int64_atomics).name;
}

std::unique_ptr<Strategy> make_full_opencl(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase, const BackendChoice& backend,
                                           bool separation_filter) {
  opencl::NarrowPhaseChoice narrow = opencl::choose_narrow_phase("full", std::move(narrow_phase));
  opencl::DeviceInfo device = opencl::choose_checked_device("full", backend.device, false);
  return std::make_unique<FullOpenCl>(std::move(narrow), std::move(device), backend, separation_filter);
}

#else

std::vector<OpenClDeviceSummary> opencl_devices() {
  throw std::invalid_argument(
      "OpenCL is not available: this build has CCDBENCH_WITH_OPENCL=OFF (install ocl-icd-opencl-dev "
      "opencl-headers pocl-opencl-icd, which scripts/setup.sh does, and reconfigure)");
}

namespace {

[[noreturn]] void refuse_without_opencl() {
  throw std::invalid_argument(
      "backend=opencl is not available: this build has CCDBENCH_WITH_OPENCL=OFF (install ocl-icd-opencl-dev "
      "opencl-headers pocl-opencl-icd, which scripts/setup.sh does, and reconfigure)");
}

}  // namespace

std::string opencl_device_name(const std::string&, const BackendChoice&, const narrowphase::ResolvedNarrowPhase&, bool) { refuse_without_opencl(); }

std::unique_ptr<Strategy> make_full_opencl(std::unique_ptr<narrowphase::NarrowPhase>, const BackendChoice&, bool) { refuse_without_opencl(); }

#endif

}  // namespace ccd::strategies
