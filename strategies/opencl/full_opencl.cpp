#include "strategies/opencl/full_opencl.hpp"

#include "strategies/face_shape.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/opencl/pipeline.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>

namespace ccd::strategies {
namespace {

using opencl::Buffer;
using opencl::upload;

/// The host narrow phase of several devices' pipelines (for the queries a device hands back): one object, called
/// from each device's thread, as it is called from many threads on one device (the narrow phases with a device form
/// are thread-safe).
class SharedNarrowPhase final : public narrowphase::NarrowPhase {
 public:
  explicit SharedNarrowPhase(std::shared_ptr<const narrowphase::NarrowPhase> shared) : shared_(std::move(shared)) {}
  std::string name() const override { return shared_->name(); }
  bool conservative() const override { return shared_->conservative(); }
  narrowphase::NarrowPhaseResult vertex_face(const narrowphase::PairRows& rows, double thickness) const override {
    return shared_->vertex_face(rows, thickness);
  }
  narrowphase::NarrowPhaseResult edge_edge(const narrowphase::PairRows& rows, double thickness) const override {
    return shared_->edge_edge(rows, thickness);
  }
  std::optional<narrowphase::DeviceForm> device_form() const override { return shared_->device_form(); }
  bool thread_safe() const override { return shared_->thread_safe(); }
  std::vector<std::pair<std::string, std::string>> provenance() const override { return shared_->provenance(); }

 private:
  std::shared_ptr<const narrowphase::NarrowPhase> shared_;
};

/// What the chunks of a step add up to (on one device, or merged over several).
struct Chunks {
  opencl::Decided decided;
  std::optional<TestedPairs> tested;
  std::size_t candidates = 0, elementary = 0, tests = 0, count = 0;
};

/// `full`'s step on one device: its own context, hierarchy, queries, positions and lists. A step on several devices
/// (device=all, device=0+1) has one of these per device, each taking ranges of the step's queries.
class DeviceWorker {
 public:
  /// `ranges`: how many ranges the step's queries are dealt into (1 on one device).
  DeviceWorker(opencl::NarrowPhaseChoice narrow_phase, opencl::DeviceInfo device, const BackendChoice& backend, bool separation_filter,
               std::size_t ranges = 1)
      : pipeline_(std::move(narrow_phase), std::move(device), backend, "full:backend=opencl"),
        separation_filter_(separation_filter),
        ranges_(ranges) {}

  opencl::DevicePipeline& pipeline() { return pipeline_; }
  const opencl::DevicePipeline& pipeline() const { return pipeline_; }
  std::size_t query_count() const { return queries_.count; }
  const std::vector<std::size_t>& range_starts() const { return queries_.range_starts; }
  const opencl::ChunkRoom& room() const { return room_; }

  void init(const Scene& scene, std::span<const Vec3> first_frame) {
    pipeline_.init(scene, first_frame);
    pipeline_.make_queries(queries_, true, true, false, ranges_);
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

  /// The step's positions on the device, its swept boxes and the refit of the moving objects' trees.
  void begin(const StepView& step, opencl::StageEvents& events) {
    positions_.begin(pipeline_.context(), step, events);
    pipeline_.vertex_boxes(positions_.x0(), positions_.x1(), events);
    pipeline_.refit(pipeline_.moving_nodes(), positions_.x0(), positions_.x1(), pipeline_.scene().thickness() / 2, nullptr, node_boxes_, &events);
  }

  /// Queries [first, end) of the step in chunks that fit the memory budget (one, where the whole range does):
  /// ranges of queries whose candidate pairs fit their list, each in ranges of candidates whose elementary pairs fit
  /// theirs, each range filtered and decided. A range that does not fit is tried again smaller; one that fits
  /// easily lets the next grow twice as large, and the spans carry over to the next range and step (a step like the
  /// last needs no retries). Every answer is the same as in one piece: the pairs a range finds are those its queries
  /// or candidates find in the whole step, each decided by the same code, and the set is put in order at the end.
  void run_queries(std::size_t first, std::size_t end, const StepView& step, StepResult& result, opencl::StageEvents& events, Chunks& chunks) {
    const Buffer& x0 = positions_.x0();
    const Buffer& x1 = positions_.x1();
    for (std::size_t q = first; q < end;) {
      const std::size_t span = std::min(query_span_, end - q);
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
  }

  void finish(const StepView& step) { positions_.finish(step); }

  std::uint64_t device_bytes() const {
    return pipeline_.bytes() + positions_.bytes() + node_boxes_.bytes() + queries_.bytes() + candidates_.buffer.bytes() + elementary_.buffer.bytes() +
           kept_.buffer.bytes();
  }

 private:
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
  std::size_t ranges_ = 1;
  opencl::Queries queries_;
  opencl::DevicePositions positions_;
  Buffer node_boxes_;
  opencl::DeviceList candidates_, elementary_, kept_;
};

/// How many ranges of a step's queries each device of several takes on average: enough that a faster device takes
/// more of them and a slower one sets no more than its share of the step's end (each range costs a traversal launch
/// and a few small downloads), few enough that each range fills a device. The queries are dealt into the ranges
/// (DevicePipeline::make_queries), so ranges cost alike and a device's share needs only a few: the 1M-triangle
/// ball's ranges cut in query order, 8 a device, cost unevenly and filled a GPU less well (reports/gpus).
constexpr std::size_t kRangesPerDevice = 2;

class FullOpenCl final : public Strategy {
 public:
  FullOpenCl(opencl::NarrowPhaseChoice narrow_phase, std::vector<opencl::DeviceInfo> devices, const BackendChoice& backend, bool separation_filter)
      : separation_filter_(separation_filter) {
    if (devices.size() == 1) {
      workers_.push_back(std::make_unique<DeviceWorker>(std::move(narrow_phase), std::move(devices[0]), backend, separation_filter));
      return;
    }
    const std::shared_ptr<const narrowphase::NarrowPhase> host(std::move(narrow_phase.host));
    for (opencl::DeviceInfo& device : devices) {
      opencl::NarrowPhaseChoice narrow{std::make_unique<SharedNarrowPhase>(host), narrow_phase.form};
      workers_.push_back(
          std::make_unique<DeviceWorker>(std::move(narrow), std::move(device), backend, separation_filter, devices.size() * kRangesPerDevice));
    }
  }

  std::vector<std::pair<std::string, std::string>> provenance() const override {
    std::vector<std::pair<std::string, std::string>> entries = workers_[0]->pipeline().provenance();
    if (workers_.size() > 1) {
      // Every device of the step: their indices and names, joined by '+'.
      for (auto& [key, value] : entries) {
        if (key != "opencl_device" && key != "opencl_device_index") continue;
        value.clear();
        for (const auto& worker : workers_) {
          const opencl::DeviceInfo& d = worker->pipeline().device();
          if (!value.empty()) value += '+';
          value += key == "opencl_device" ? d.name : std::to_string(d.index);
        }
      }
    }
    return entries;
  }

  std::string name() const override {
    const opencl::DevicePipeline& first = workers_[0]->pipeline();
    const opencl::NarrowPhaseChoice& narrow = first.narrow_phase();
    return "full+" + narrow.host->name() + (separation_filter_ ? ":filter=on" : "") + first.backend().resolved(device_name(), narrow.conservative());
  }

  void prepare() override {
    for (const auto& worker : workers_) worker->pipeline().prepare();
  }

  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    if (workers_.size() == 1) {
      workers_[0]->init(scene, first_frame);
      return;
    }
    run_on_every_device([&](DeviceWorker& worker, std::size_t) { worker.init(scene, first_frame); });
  }

  StepResult step(const StepView& step, bool audit) override {
    const auto started = std::chrono::steady_clock::now();
    StepResult result;
    Chunks chunks;
    if (audit) chunks.tested.emplace();
    std::vector<opencl::StageEvents> events(workers_.size());
    if (workers_.size() == 1) {
      DeviceWorker& worker = *workers_[0];
      worker.begin(step, events[0]);
      worker.run_queries(0, worker.query_count(), step, result, events[0], chunks);
    } else {
      // Each device takes the next range of queries until none is left: the answers are the same as on one device
      // (each range's pairs are those its queries find in the whole step, and the set is put in order at the end).
      const std::vector<std::size_t>& starts = workers_[0]->range_starts();
      std::atomic<std::size_t> next{0};
      std::vector<Chunks> parts(workers_.size());
      std::vector<StepResult> partial(workers_.size());
      run_on_every_device([&](DeviceWorker& worker, std::size_t k) {
        if (audit) parts[k].tested.emplace();
        worker.begin(step, events[k]);
        for (std::size_t r = next.fetch_add(1); r + 1 < starts.size(); r = next.fetch_add(1)) {
          worker.run_queries(starts[r], starts[r + 1], step, partial[k], events[k], parts[k]);
        }
        // A device that got no range has only its upload and refit queued: done before its events are read.
        worker.pipeline().context().finish();
      });
      for (std::size_t k = 0; k < workers_.size(); ++k)
        merge(std::move(parts[k]), partial[k], 1.0 / static_cast<double>(workers_.size()), chunks, result);
    }
    DeviceWorker& first = *workers_[0];
    first.pipeline().collect(chunks.decided, result);
    // On several devices, a device stage's time is its mean over the devices (their sum would pass the step's wall
    // time, which the stages add up to), as are the host stages each device's thread timed (merge).
    const double share = 1.0 / static_cast<double>(workers_.size());
    for (opencl::StageEvents& device_events : events) {
      for (const auto& [stage, milliseconds] : device_events.collect()) result.stages.add(stage, milliseconds * share);
    }
    double span = 0, idle = 0;
    for (const opencl::StageEvents& device_events : events) {
      span = std::max(span, device_events.span_milliseconds());
      idle += device_events.idle_milliseconds();
    }
    result.counters.extra.emplace_back("device_span_ms", span);
    result.counters.extra.emplace_back("device_idle_ms", idle);
    if (audit) {
      opencl::DevicePipeline::sort_tested(*chunks.tested);
      result.tested = std::move(chunks.tested);
    }
    if (separation_filter_) result.counters.extra.emplace_back("distance_filtered", static_cast<double>(chunks.elementary - chunks.tests));
    result.counters.extra.emplace_back(kDeviceChunksCounter, static_cast<double>(std::max<std::size_t>(chunks.count, 1)));
    if (workers_.size() > 1) result.counters.extra.emplace_back("devices", static_cast<double>(workers_.size()));
    std::uint64_t budget = 0, fixed = 0, bytes = 0;
    for (const auto& worker : workers_) {
      budget += worker->room().budget;
      fixed += worker->room().fixed;
      bytes += worker->device_bytes();
      worker->finish(step);
    }
    result.counters.extra.emplace_back(kDeviceBudgetCounter, static_cast<double>(budget));
    result.counters.extra.emplace_back("device_fixed_bytes", static_cast<double>(fixed));
    // Face-shape pairs on the host, with the host's narrow phase (face_shape.hpp), as the CPU backend does.
    run_face_shape_stage(result, first.pipeline().scene(), step, *first.pipeline().narrow_phase().host, audit);
    result.counters.candidate_triangle_pairs = chunks.candidates;
    result.counters.elementary_tests = chunks.tests;
    result.counters.device_bytes = bytes;
    opencl::add_launch_and_wait(result, started);
    return result;
  }

 private:
  /// The device part of the resolved name: the device's name, or the indices of several joined by '+' (a name
  /// selects the first device that has it, and several devices often share one).
  std::string device_name() const {
    if (workers_.size() == 1) return workers_[0]->pipeline().device().name;
    std::string indices;
    for (const auto& worker : workers_) {
      if (!indices.empty()) indices += '+';
      indices += std::to_string(worker->pipeline().device().index);
    }
    return indices;
  }

  /// Calls `work(worker, k)` for every device at once, one host thread each; the first exception is rethrown.
  template <class Work>
  void run_on_every_device(Work&& work) {
    std::vector<std::exception_ptr> errors(workers_.size());
    std::vector<std::thread> threads;
    try {
      for (std::size_t k = 0; k < workers_.size(); ++k) {
        threads.emplace_back([&, k] {
          try {
            work(*workers_[k], k);
          } catch (...) {
            errors[k] = std::current_exception();
          }
        });
      }
    } catch (...) {
      // A thread that could not be started: the started ones are waited for before the error goes on.
      for (std::thread& thread : threads) thread.join();
      throw;
    }
    for (std::thread& thread : threads) thread.join();
    for (const std::exception_ptr& error : errors) {
      if (error) std::rethrow_exception(error);
    }
  }

  /// One device's part of a step added to the whole.
  static void merge(Chunks&& part, StepResult& partial, double share, Chunks& into, StepResult& result) {
    opencl::Decided& d = into.decided;
    d.pairs.insert(d.pairs.end(), part.decided.pairs.begin(), part.decided.pairs.end());
    d.toi.insert(d.toi.end(), part.decided.toi.begin(), part.decided.toi.end());
    d.given_up += part.decided.given_up;
    d.second_pass += part.decided.second_pass;
    d.third_pass += part.decided.third_pass;
    d.deep_pass += part.decided.deep_pass;
    d.deep_colliding += part.decided.deep_colliding;
    d.on_host += part.decided.on_host;
    d.second_pass_ms += part.decided.second_pass_ms;
    d.third_pass_ms += part.decided.third_pass_ms;
    d.deep_pass_ms += part.decided.deep_pass_ms;
    if (into.tested && part.tested) {
      TestedPairs& t = *into.tested;
      t.vertex_face.insert(t.vertex_face.end(), part.tested->vertex_face.begin(), part.tested->vertex_face.end());
      t.edge_edge.insert(t.edge_edge.end(), part.tested->edge_edge.begin(), part.tested->edge_edge.end());
    }
    into.candidates += part.candidates;
    into.elementary += part.elementary;
    into.tests += part.tests;
    into.count += part.count;
    for (const auto& [stage, milliseconds] : partial.stages.entries()) result.stages.add(stage, milliseconds * share);
  }

  std::vector<std::unique_ptr<DeviceWorker>> workers_;
  bool separation_filter_ = false;
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
  if (opencl::names_several_devices(backend.device)) {
    if (int64_atomics) opencl::choose_checked_device(strategy, backend.device, true);  // refuses, naming why
    std::string indices;
    for (const opencl::DeviceInfo& d : opencl::choose_checked_devices(strategy, backend.device)) {
      if (!indices.empty()) indices += '+';
      indices += std::to_string(d.index);
    }
    return indices;
  }
  return opencl::choose_checked_device(strategy, backend.device, int64_atomics).name;
}

std::unique_ptr<Strategy> make_full_opencl(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase, const BackendChoice& backend,
                                           bool separation_filter) {
  opencl::NarrowPhaseChoice narrow = opencl::choose_narrow_phase("full", std::move(narrow_phase));
  std::vector<opencl::DeviceInfo> devices = opencl::choose_checked_devices("full", backend.device);
  return std::make_unique<FullOpenCl>(std::move(narrow), std::move(devices), backend, separation_filter);
}

}  // namespace ccd::strategies
