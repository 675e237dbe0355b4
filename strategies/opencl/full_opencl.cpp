#include "strategies/opencl/full_opencl.hpp"

#include "ccd/config.hpp"
#include "strategies/face_shape.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"

#if CCDBENCH_WITH_OPENCL
#include "strategies/opencl/pipeline.hpp"
#endif

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <optional>
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
    // What every step keeps (the swept vertex boxes included, made by the first step), then the lists' room.
    const std::uint64_t vertex_boxes = std::max<std::size_t>(scene.topology().num_vertices(), 1) * 6 * sizeof(double);
    use_room(pipeline_.plan_room(pipeline_.bytes() + positions_.bytes() + node_boxes_.bytes() + queries_.bytes() + vertex_boxes));
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
    Chunks chunks;
    if (audit) chunks.tested.emplace();
    run_chunks(step, x0, x1, result, events, chunks);
    pipeline_.collect(chunks.decided, result);
    for (const auto& [stage, milliseconds] : events.collect()) result.stages.add(stage, milliseconds);
    result.counters.extra.emplace_back("device_span_ms", events.span_milliseconds());
    result.counters.extra.emplace_back("device_idle_ms", events.idle_milliseconds());
    if (audit) {
      opencl::DevicePipeline::sort_tested(*chunks.tested);
      result.tested = std::move(chunks.tested);
    }
    if (separation_filter_) result.counters.extra.emplace_back("distance_filtered", static_cast<double>(chunks.elementary - chunks.tests));
    result.counters.extra.emplace_back("device_chunks", static_cast<double>(chunks.count));
    result.counters.extra.emplace_back("device_budget_bytes", static_cast<double>(room_.budget));
    result.counters.extra.emplace_back("device_fixed_bytes", static_cast<double>(room_.fixed));
    positions_.finish(step);
    // Face-shape pairs on the host, with the host's narrow phase (face_shape.hpp), as the CPU backend does.
    run_face_shape_stage(result, pipeline_.scene(), step, *pipeline_.narrow_phase().host, audit);
    result.counters.candidate_triangle_pairs = chunks.candidates;
    result.counters.elementary_tests = chunks.tests;
    result.counters.device_bytes = pipeline_.bytes() + positions_.bytes() + node_boxes_.bytes() + queries_.bytes() + candidates_.buffer.bytes() +
                                   elementary_.buffer.bytes() + kept_.buffer.bytes();
    opencl::add_launch_and_wait(result, started);
    return result;
  }

 private:
  /// What the chunks of a step add up to.
  struct Chunks {
    opencl::Decided decided;
    std::optional<TestedPairs> tested;
    std::size_t candidates = 0, elementary = 0, tests = 0, count = 0;
  };

  /// A range of `span` items whose list needed `found` entries (kListOverflow: past 2^32) where `limit` fit: the
  /// span to try instead, smaller by the overshoot with a fifth to spare. (A span of 1 always fits where this is
  /// called: one candidate's 15 elementary pairs fit every room, and one query's candidates widen the room.)
  static std::size_t smaller_span(std::size_t span, std::size_t found, std::size_t limit) {
    if (span <= 1) throw std::logic_error("a range of one item did not fit its list");
    const double fit = found == opencl::kListOverflow ? 0.5 : 0.8 * static_cast<double>(limit) / static_cast<double>(found);
    return std::clamp<std::size_t>(static_cast<std::size_t>(static_cast<double>(span) * fit), 1, span - 1);
  }

  /// The lists' room (planned at init, and again for a query that found more candidate pairs than the room held):
  /// a list that holds more than its new room gives it back.
  void use_room(const opencl::ChunkRoom& room) {
    room_ = room;
    candidates_.set_limit(room.candidates, sizeof(cl_uint2));
    elementary_.set_limit(room.elementary, sizeof(cl_uint4));
    kept_.set_limit(room.elementary, sizeof(cl_uint4));
  }

  /// The step in chunks that fit the memory budget (one, where the whole step does): ranges of queries whose
  /// candidate pairs fit their list, each in ranges of candidates whose elementary pairs fit theirs, each range
  /// filtered and decided. A range that does not fit is tried again smaller; one that fits easily lets the next grow
  /// twice as large, and the spans carry over to the next range and step (a step like the last needs no retries).
  /// Every answer is the same as in one piece: the pairs a range finds are those its queries or candidates find in
  /// the whole step, each decided by the same code, and the set is put in order at the end.
  void run_chunks(const StepView& step, const Buffer& x0, const Buffer& x1, StepResult& result, opencl::StageEvents& events, Chunks& chunks) {
    for (std::size_t q = 0; q < queries_.count;) {
      const std::size_t span = std::min(query_span_, queries_.count - q);
      const std::size_t found = pipeline_.traverse(queries_, node_boxes_, nullptr, candidates_, events, "traversal", q, span);
      if (found > candidates_.limit) {
        if (span == 1) {
          // One query found more than the room held: the room is planned again for it, or the budget refused
          // naming what this query needs.
          if (found == opencl::kListOverflow) throw std::runtime_error(pipeline_.label() + ": one query found 2^32 candidate pairs or more");
          use_room(pipeline_.plan_room(room_.fixed, found));
        } else {
          query_span_ = smaller_span(span, found, candidates_.limit);
        }
        continue;
      }
      chunks.candidates += found;
      run_candidate_chunks(found, step, x0, x1, result, events, chunks);
      q += span;
      if (found < candidates_.limit / 2 && span == query_span_) query_span_ = std::min(query_span_, queries_.count) * 2;
    }
    chunks.count = std::max<std::size_t>(chunks.count, 1);  // a step without candidate pairs is one piece
  }

  void run_candidate_chunks(std::size_t found, const StepView& step, const Buffer& x0, const Buffer& x1, StepResult& result,
                            opencl::StageEvents& events, Chunks& chunks) {
    for (std::size_t c = 0; c < found;) {
      const std::size_t span = std::min(candidate_span_, found - c);
      const std::size_t elementary = pipeline_.expand(candidates_.buffer, span, elementary_, events, c);
      if (elementary > elementary_.limit) {
        candidate_span_ = smaller_span(span, elementary, elementary_.limit);
        continue;
      }
      const opencl::DeviceList* tested = &elementary_;
      if (separation_filter_) {
        pipeline_.filter(elementary_.buffer, elementary, x0, x1, kept_, events);
        tested = &kept_;
      }
      const std::size_t tests = separation_filter_ ? kept_.count : elementary;
      pipeline_.decide(tested->buffer, tests, step, x0, x1, result, events, chunks.decided);
      if (chunks.tested) pipeline_.add_tested_pairs(tested->buffer, tests, *chunks.tested);
      chunks.elementary += elementary;
      chunks.tests += tests;
      ++chunks.count;
      c += span;
      if (elementary < elementary_.limit / 2 && span == candidate_span_) candidate_span_ = std::min(candidate_span_, found) * 2;
    }
  }

  opencl::DevicePipeline pipeline_;
  opencl::ChunkRoom room_;
  /// The ranges that fit last (queries, candidates): where the next step starts.
  std::size_t query_span_ = static_cast<std::size_t>(-1), candidate_span_ = static_cast<std::size_t>(-1);
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
