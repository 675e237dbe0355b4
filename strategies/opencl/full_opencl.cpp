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
#include <vector>

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
    lists_sized_ = false;
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
    // The stages from traversal to the compaction of what collides run as one chain: each kernel reads the count of
    // the list before it on the device, and the host waits once, for every count (read_counts). A list that did not
    // fit is grown and the stages from it run again (lists keep their room); when only the compaction's list
    // overflowed, the compaction alone. The first step of a run waits for each count instead: its lists start
    // with room from the scene, not from a step, and a chain run on a list that overflowed is work thrown away.
    opencl::DeviceList& kept = pipeline_.kept();
    opencl::DeviceList& tested = separation_filter_ ? kept_ : elementary_;
    std::vector<opencl::DeviceList*> lists = {&candidates_, &elementary_};
    std::vector<const char*> stages = {"traversal", "expansion"};
    if (separation_filter_) {
      lists.push_back(&kept_);
      stages.push_back("distance heuristic");
    }
    lists.push_back(&kept);
    stages.push_back("narrow phase");
    const auto enqueued = lists_sized_ ? opencl::Fill::enqueue : opencl::Fill::wait;
    for (std::size_t from = 0; from < lists.size();) {
      if (from == 0) pipeline_.traverse(queries_, node_boxes_, nullptr, candidates_, events, "traversal", enqueued);
      if (from <= 1) pipeline_.expand(candidates_.buffer, candidates_.items(), elementary_, events, enqueued);
      if (separation_filter_ && from <= 2) pipeline_.filter(elementary_.buffer, elementary_.items(), x0, x1, kept_, events, enqueued);
      if (from + 1 < lists.size()) pipeline_.narrow(tested.buffer, tested.items(), x0, x1, events);
      pipeline_.compact(tested.buffer, tested.items(), events, enqueued);
      from = pipeline_.read_counts(lists, stages);
      pipeline_.check_candidate_count(candidates_.total[0]);
    }
    lists_sized_ = true;
    const std::size_t candidates = candidates_.count, elementary = elementary_.count, tests = tested.count;
    pipeline_.collect(step, x0, x1, result, events);
    for (const auto& [stage, milliseconds] : events.collect()) result.stages.add(stage, milliseconds);
    result.counters.extra.emplace_back("device_span_ms", events.span_milliseconds());
    result.counters.extra.emplace_back("device_idle_ms", events.idle_milliseconds());
    if (audit) result.tested = pipeline_.tested_pairs(tested.buffer, tests);
    if (separation_filter_) result.counters.extra.emplace_back("distance_filtered", static_cast<double>(elementary - tests));
    positions_.finish(step);
    // Face-shape pairs on the host, with the host's narrow phase (face_shape.hpp), as the CPU backend does.
    run_face_shape_stage(result, pipeline_.scene(), step, *pipeline_.narrow_phase().host, audit);
    result.counters.candidate_triangle_pairs = candidates;
    result.counters.elementary_tests = tests;
    result.counters.device_bytes = pipeline_.bytes() + positions_.bytes() + node_boxes_.bytes() + queries_.bytes() + candidates_.bytes() +
                                    elementary_.bytes() + kept_.bytes();
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
  /// Whether a step has sized the lists (init leaves room from the scene only).
  bool lists_sized_ = false;
};

}  // namespace

std::vector<OpenClDeviceSummary> opencl_devices() {
  std::vector<OpenClDeviceSummary> summaries;
  for (const opencl::DeviceInfo& d : opencl::list_devices()) {
    OpenClDeviceSummary s{d.index, d.platform, d.name, d.version, d.driver, d.is_gpu, d.compute_units, d.global_memory, d.fp64, d.fp64_denormals,
                          d.int64_atomics, ""};
    try {
      opencl::require_double_precision(d);
    } catch (const std::invalid_argument& refusal) {
      s.refused_because = refusal.what();
    }
    summaries.push_back(std::move(s));
  }
  return summaries;
}

std::unique_ptr<Strategy> make_full_opencl(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase, const BackendChoice& backend,
                                           bool separation_filter) {
  opencl::NarrowPhaseChoice narrow = opencl::choose_narrow_phase("full", std::move(narrow_phase));
  opencl::DeviceInfo device = opencl::choose_device(opencl::list_devices(), backend.device);
  opencl::require_double_precision(device);
  return std::make_unique<FullOpenCl>(std::move(narrow), std::move(device), backend, separation_filter);
}

#else

std::vector<OpenClDeviceSummary> opencl_devices() {
  throw std::invalid_argument("OpenCL is not available: this build has CCDBENCH_WITH_OPENCL=OFF (install ocl-icd-opencl-dev "
                              "opencl-headers pocl-opencl-icd, which scripts/setup.sh does, and reconfigure)");
}

std::unique_ptr<Strategy> make_full_opencl(std::unique_ptr<narrowphase::NarrowPhase>, const BackendChoice&, bool) {
  throw std::invalid_argument("backend=opencl is not available: this build has CCDBENCH_WITH_OPENCL=OFF (install ocl-icd-opencl-dev "
                              "opencl-headers pocl-opencl-icd, which scripts/setup.sh does, and reconfigure)");
}

#endif

}  // namespace ccd::strategies
