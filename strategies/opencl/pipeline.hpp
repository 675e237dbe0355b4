#pragma once
/// @file
/// What every strategy of the OpenCL backend does the same way (kernels/full.cl): the device's context and its
/// arithmetic self-test, the scene's topology and assignment masks on the device, each object's hierarchy built on
/// the host exactly as the CPU's and refitted level by level, traversal queries, lists of unknown length, the
/// expansion of candidate triangle pairs into elementary pairs, and the back end: the narrow phase with its tiers
/// for queries the device gives up, down to the collision set. `full:backend=opencl` is this pipeline run whole
/// every step; `apccd:backend=opencl` (strategies/apccd/opencl) adds its sessions around it.
///
/// Only for sources built with CCDBENCH_WITH_OPENCL.

#include "core/scene.hpp"
#include "core/step.hpp"
#include "strategies/backend.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"
#include "strategies/opencl/runtime.hpp"
#include "strategies/strategy.hpp"

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace ccd::opencl {

/// The narrow phase a pipeline runs: the host's instance (for the queries the device hands on, and the face-shape
/// stage) and the form its kernel takes, with the host's settings.
struct NarrowPhaseChoice {
  std::unique_ptr<narrowphase::NarrowPhase> host;
  narrowphase::DeviceForm form;
  bool conservative() const { return form.kernel == narrowphase::DeviceForm::Kernel::conservative; }
};

/// The narrow phase of `strategy`:backend=opencl.
/// @throws std::invalid_argument for a narrow phase without a device form, naming those that have one.
NarrowPhaseChoice choose_narrow_phase(const std::string& strategy, std::unique_ptr<narrowphase::NarrowPhase> host);

/// The device `selector` chooses (device=), checked for what `strategy`:backend=opencl needs: fp64 that keeps
/// subnormals, and 64-bit atomics where `int64_atomics` (apccd's pending list). @throws std::invalid_argument.
DeviceInfo choose_checked_device(const std::string& strategy, const std::string& selector, bool int64_atomics);
/// The devices `selector` names (choose_devices), each checked so: `full` runs a step over several.
std::vector<DeviceInfo> choose_checked_devices(const std::string& strategy, const std::string& selector);

/// @throws std::invalid_argument: `strategy`:backend=opencl runs the narrow phases that have a device form, not `name`.
[[noreturn]] void refuse_host_narrow_phase(const std::string& strategy, const std::string& name);

/// An empty slot of apccd's pending table (CCD_EMPTY_KEY in its kernels): no pair key (a, b), a < b, is all ones.
inline constexpr cl_ulong kEmptyPendingKey = ~cl_ulong{0};

/// The kernels' build options: every constant the host and the kernels must agree on, from its one definition on
/// the host (the kernel files refuse to build without them), and the sizes chosen for this device and run.
std::string kernel_defines(std::size_t group_size, long sub_boxes);

/// A list the device fills: its buffer, its room (entries) and, after a fill, its length. With a limit (entries,
/// from the memory budget) it never grows past it: a fill that would need more returns its total without filling,
/// and the caller fills a smaller range.
struct DeviceList {
  Buffer buffer;
  std::size_t capacity = 0;
  std::size_t count = 0;
  std::size_t limit = 0;  // 0: none
  /// Sets the limit; a buffer that holds more than it gives its memory back (reserved again within it when filled).
  void set_limit(std::size_t entries, std::size_t entry_bytes) {
    limit = entries;
    buffer.release_above(entries * entry_bytes);
  }
};

/// What a fill returns when its count passed 2^32 entries in one range (a budgeted list: fill a smaller range).
inline constexpr std::size_t kListOverflow = static_cast<std::size_t>(-1);

/// The deep pass's sub-box store, in device bytes per elementary pair of a budgeted chunk (part of
/// kBytesPerElementary). The queries that overflow a work item's sub-boxes are few (about 6,400 a step in the
/// paper's pile at δ = 0, reports/gpus), each needing kDeepSubBoxFactor * kSubBoxBytes (43 kB at the default
/// sub_boxes); a chunk whose store has no room for one query leaves them to the host.
inline constexpr std::size_t kDeepStoreBytesPerElementary = 8;
/// Device bytes a chunk of a step holds per elementary pair: the expansion's list (16), the filter's flag and kept
/// list (1 + 16), the narrow phase's status and TOI (1 + 8), what it keeps (16 + 1 + 8), the retries of the
/// queries it gives up (16 + 1 + 8) and the deep pass's store; and per candidate triangle pair (its two faces).
inline constexpr std::size_t kBytesPerElementary = 92 + kDeepStoreBytesPerElementary;
/// The deep pass (DevicePipeline::deep_pass) gives each query that overflowed a work item's sub-boxes this many
/// times as many, in device memory: 768 at the default 48, six times the host's first try (128, inclusion.cpp), so
/// that nearly every such query ends on the device; one that overflows these too is decided on the host.
inline constexpr std::size_t kDeepSubBoxFactor = 16;
/// The most device memory the deep pass's store takes at once (without a tighter budget): 256 MiB, room for 6,200
/// queries at 768 sub-boxes, about what one step of the paper's pile hands back; more run in turn.
inline constexpr std::size_t kDeepStoreMaxBytes = std::size_t{256} << 20;
inline constexpr std::size_t kBytesPerCandidate = 2 * sizeof(cl_uint);
/// A chunk has room for at least one query's candidate pairs (a face against its neighbours and what it sweeps
/// through: a few dozen in the densest public step) and one candidate's elementary pairs (15).
inline constexpr std::size_t kMinimumChunkCandidates = 256;
inline constexpr std::size_t kMinimumChunkElementary = 15;

/// The room the memory budget leaves a step's lists, once the fixed buffers (topology, hierarchies, positions,
/// queries) are counted.
struct ChunkRoom {
  std::uint64_t budget = 0, fixed = 0;
  std::size_t candidates = 0, elementary = 0;
};

/// What the narrow phase decided over the chunks of a step: the colliding pairs with their TOIs, and its counts.
struct Decided {
  std::vector<cl_uint4> pairs;
  std::vector<double> toi;
  std::size_t given_up = 0, second_pass = 0, third_pass = 0, deep_pass = 0, deep_colliding = 0, on_host = 0;
  /// Wall time of the later device passes (within the "narrow phase" stage).
  double second_pass_ms = 0, third_pass_ms = 0, deep_pass_ms = 0;
};

/// Traversal queries: face q_face[i] (its leaf q_leaf[i], whose box is the query) against the tree rooted at
/// q_root[i]; self queries keep the faces after it only. Pair queries of object_pairs=session read a translation box
/// (q_offset[i], 6 doubles in offsets) that sweeps the query's box (mode 2) or the tree's boxes (mode 3).
struct Queries {
  Buffer leaf, face, root, mode, offset_index;
  std::size_t count = 0;
  /// Where each of the ranges the queries were dealt into starts, and the end: {0, count} for one range.
  std::vector<std::size_t> range_starts;
  std::size_t bytes() const { return leaf.bytes() + face.bytes() + root.bytes() + mode.bytes() + offset_index.bytes(); }
};

/// The order that deals blocks of `count` queries round-robin into `ranges` ranges (block j to range j mod ranges),
/// and where each range starts in it (plus the end): each range holds every part of the step alike
/// (DevicePipeline::make_queries).
std::pair<std::vector<std::size_t>, std::vector<std::size_t>> deal_into_ranges(std::size_t count, std::size_t ranges);

/// A step's positions on the device, in two buffers that swap roles: x1 of one step is x0 of the next, so a step
/// that follows the last uploads x1 only.
class DevicePositions {
 public:
  /// Both ends hold `frame` (what init fits static objects over), and no step came before.
  void reset(Context& context, std::span<const Vec3> frame);
  /// Uploads `step`'s x1, and its x0 unless it follows the last step; end the step with finish().
  void begin(Context& context, const StepView& step, StageEvents& events);
  const Buffer& x0() const { return x_[current_]; }
  const Buffer& x1() const { return x_[1 - current_]; }
  /// The step is done: its x1 becomes the next step's x0.
  void finish(const StepView& step);
  std::size_t bytes() const { return x_[0].bytes() + x_[1].bytes(); }

 private:
  Buffer x_[2];
  std::size_t current_ = 0;
  std::size_t last_step_ = static_cast<std::size_t>(-1);
};

/// The refit of a set of leaves and of their ancestors.
struct RefitPlan {
  Buffer leaves;
  std::size_t leaf_count = 0;
  /// Internal nodes, deepest level first; level i is [level_offsets[i], level_offsets[i + 1]) (also on the device,
  /// as offsets, for the levels refitted by one work group).
  Buffer levels;
  std::vector<std::size_t> level_offsets;
  Buffer offsets;
};

class DevicePipeline {
 public:
  /// `label` names the strategy in errors ("full:backend=opencl"); `backend` its backend keys.
  DevicePipeline(NarrowPhaseChoice narrow_phase, DeviceInfo device, strategies::BackendChoice backend, std::string label);

  /// The context (leased: lease_context) and the device's arithmetic self-test, once; for a conservative narrow phase,
  /// the deep pass's program too.
  void prepare();
  /// Context, self-test, topology, masks and the flattened hierarchies (shape only; boxes come from refits).
  void init(const Scene& scene, std::span<const Vec3> first_frame);

  Context& context() { return *context_; }
  const Scene& scene() const { return *scene_; }
  std::size_t group() const { return group_; }
  const strategies::BackendChoice& backend() const { return backend_; }
  /// The room a list starts with: `sized` (from the scene), unless list_start says otherwise.
  std::size_t list_start(std::size_t sized) const { return backend_.list_start != 0 ? backend_.list_start : sized; }
  const std::string& label() const { return label_; }
  const NarrowPhaseChoice& narrow_phase() const { return narrow_phase_; }
  const DeviceInfo& device() const { return device_; }
  /// The device as results record it: platform, device and its index (`ccdbench devices`: which of two alike GPUs
  /// a rank took), its OpenCL version and driver.
  std::vector<std::pair<std::string, std::string>> provenance() const {
    return {{"opencl_platform", device_.platform},
            {"opencl_device", device_.name},
            {"opencl_device_index", std::to_string(device_.index)},
            {"opencl_version", device_.version},
            {"opencl_driver", device_.driver}};
  }

  // Topology on the device.
  const Buffer& faces() const { return faces_; }
  std::size_t node_count() const { return node_count_; }
  /// Every node (at init: static objects too) and the moving objects' nodes.
  const RefitPlan& all_nodes() const { return all_; }
  const RefitPlan& moving_nodes() const { return moving_; }
  /// Leaf node of each face, and the root of each object's tree (-1: no faces), on the host.
  const std::vector<cl_uint>& leaf_node() const { return leaf_node_; }
  const std::vector<cl_int>& roots() const { return roots_; }
  const Buffer& leaf_node_buffer() const { return leaf_node_buffer_; }
  const Buffer& children() const { return children_; }
  const Buffer& node_face() const { return node_face_; }
  /// Work-group size of a narrow-phase-like kernel (one heavy query per item): 64, or less where its resources
  /// allow less. Always the same for a kernel: PoCL compiles a kernel anew for each work-group size it meets.
  std::size_t narrow_group(cl_kernel kernel) const;

  /// Self queries (each face of a self-colliding object against its own tree) and/or pair queries (for each
  /// collidable pair, the faces of the larger object against the smaller one's tree: the other way round, a
  /// two-triangle ground would be two work items walking the whole cloth). With `offsets`, pair queries sweep by
  /// the pair's translation box (index = position in the scene's collidable pairs, for (a, b): b relative to a).
  /// With `ranges` > 1 (a step on several devices), the queries are dealt into that many ranges of equal work
  /// (Queries::range_starts; see kDealtBlock).
  void make_queries(Queries& queries, bool self, bool pairs, bool offsets, std::size_t ranges = 1);

  /// Leaf boxes of the plan over x0 -> x1, widened by `inflation` plus, with `budget` (per vertex), the largest
  /// budget of the face's corners; then every level of the plan.
  void refit(const RefitPlan& plan, const Buffer& x0, const Buffer& x1, double inflation, const Buffer* budget, const Buffer& node_boxes,
             StageEvents* events);
  /// The levels of the plan only (after leaves changed).
  void refit_levels(const RefitPlan& plan, const Buffer& node_boxes, StageEvents* events);

  /// Runs a list-filling kernel: resets the counter, launches over `items` with the list's room, reads the total;
  /// when the list did not fit, grows it to the total and runs again. Returns the total (also in list.count).
  template <class SetArguments>
  std::size_t fill_list(const char* kernel_name, std::size_t items, DeviceList& list, std::size_t entry_bytes, StageEvents& events, const char* stage,
                        SetArguments set, std::size_t first = 0);

  /// Candidate triangle pairs of `queries` against `node_boxes` (offsets: 6 doubles per collidable pair, or none);
  /// of queries [first, first + count) only, when given.
  std::size_t traverse(const Queries& queries, const Buffer& node_boxes, const Buffer* offsets, DeviceList& out, StageEvents& events,
                       const char* stage, std::size_t first = 0, std::size_t count = static_cast<std::size_t>(-1));
  /// Swept vertex boxes x0 ∪ x1 widened by δ/2 (the expansion's primitive-level box test).
  void vertex_boxes(const Buffer& x0, const Buffer& x1, StageEvents& events);
  /// Elementary pairs of `count` candidates in `candidates` that pass the primitive-level box test; of candidates
  /// [first, first + count) with a budgeted list (a step in chunks), whose count may be any.
  std::size_t expand(const Buffer& candidates, std::size_t count, DeviceList& out, StageEvents& events, std::size_t first = 0);
  /// The separation filter (narrowphase/shared/separation.h) over `count` elementary pairs: those it cannot prove
  /// apart go to `out` (in any order). Returns their count.
  std::size_t filter(const Buffer& elementary, std::size_t count, const Buffer& x0, const Buffer& x1, DeviceList& out, StageEvents& events);
  /// The narrow phase over `count` elementary pairs, then the tiers for given-up queries, into result.collisions
  /// (normalised) and the device_* / host_decided_pairs counters: decide() then collect().
  void back_end(const Buffer& elementary, std::size_t count, const StepView& step, const Buffer& x0, const Buffer& x1, strategies::StepResult& result,
                StageEvents& events);
  /// The narrow phase and its tiers over one chunk's `count` elementary pairs: their colliding pairs added to `into`.
  void decide(const Buffer& elementary, std::size_t count, const StepView& step, const Buffer& x0, const Buffer& x1, strategies::StepResult& result,
              StageEvents& events, Decided& into);
  /// The collision set (normalised) and counters of what every chunk decided.
  void collect(const Decided& decided, strategies::StepResult& result) const;
  /// The first `count` elementary pairs of `elementary`, sorted (audit mode).
  strategies::TestedPairs tested_pairs(const Buffer& elementary, std::size_t count);
  /// The same, added to `tested` unsorted (a chunk's); sort_tested() once every chunk's is in.
  void add_tested_pairs(const Buffer& elementary, std::size_t count, strategies::TestedPairs& tested);
  static void sort_tested(strategies::TestedPairs& tested);

  /// The room the memory budget (memory=) leaves a step's lists over `fixed` bytes of buffers every step keeps,
  /// with room for at least `candidates` candidate pairs (one query's); every later reserve of the narrow phase's
  /// per-pair buffers stays within it, and those that hold more (planned again, for a query that found more) are
  /// given back.
  /// @throws std::invalid_argument when the budget is below the fixed buffers and that least room (naming the
  /// minimum: for the scene as far as it is known, one query's candidates being unknown before it runs), or more
  /// than the device has.
  ChunkRoom plan_room(std::uint64_t fixed, std::size_t candidates = kMinimumChunkCandidates);
  /// The memory budget on this device, in bytes. @throws std::invalid_argument when it is more than the device has.
  std::uint64_t budget_bytes() const;

  /// Bytes of the pipeline's own buffers.
  std::size_t bytes() const;
  /// For a strategy that holds a step whole within its memory budget (apccd): `limit` tells, when the deep pass
  /// runs, the most the pipeline's own buffers may hold (what the budget leaves over the strategy's). The deep
  /// pass's store stays within what the other buffers leave of it; the host decides the queries it has no room for.
  void limit_own_bytes(std::function<std::size_t()> limit) { own_bytes_limit_ = std::move(limit); }

  /// Each candidate yields at most 15 elementary pairs (6 vertex-face, 9 edge-edge): this keeps their count in 32 bits.
  static constexpr std::size_t kMaxCandidatesPerStep = 0xFFFFFFFFull / 15;

 private:
  void build_hierarchies(const Scene& scene, std::span<const Vec3> first_frame);
  void launch_conservative(const Buffer& pairs, std::size_t count, long limit, const Buffer& status, const Buffer& toi, const Buffer& x0,
                           const Buffer& x1, StageEvents& events);
  /// narrow_conservative_deep over `count` pairs into retry_status_ and retry_toi_, with deep_sub_boxes() each in
  /// deep_store_ (deep_pass reserves it for its batches).
  void launch_deep(const Buffer& pairs, std::size_t count, const Buffer& x0, const Buffer& x1, StageEvents& events);
  /// The queries `which` of `pairs` run again on the device, their status and TOI updated: with the narrow phase's
  /// kernel and `limit`, or (deep) in the deep pass's build with kDeepSubBoxFactor times the sub-boxes each, from
  /// deep_store_.
  void device_pass(StageEvents& events, const std::vector<std::size_t>& which, long limit, const std::vector<cl_uint4>& pairs,
                   std::vector<cl_uchar>& status, std::vector<double>& toi, const Buffer& x0, const Buffer& x1, bool deep = false);
  /// The queries `which` (status 3: out of a work item's sub-boxes) through the deep pass, as many at once as the
  /// store's room holds (deep_batch); those that overflow it too keep status 3. Adds how many it ran (none when the
  /// room holds not one query: a tight memory budget, and the host decides them), how many of them collide, and
  /// its wall time to `into`.
  void deep_pass(StageEvents& events, const std::vector<std::size_t>& which, const std::vector<cl_uint4>& pairs, std::vector<cl_uchar>& status,
                 std::vector<double>& toi, const Buffer& x0, const Buffer& x1, Decided& into);
  /// Queries the deep pass's store holds at once: within kDeepStoreMaxBytes and the largest allocation, within
  /// kDeepStoreBytesPerElementary of each pair a budgeted chunk has room for (plan_room), and within what
  /// limit_own_bytes leaves over the pipeline's other buffers.
  std::size_t deep_batch() const;
  /// Sub-boxes of each query in the deep pass.
  std::size_t deep_sub_boxes() const;

  NarrowPhaseChoice narrow_phase_;
  DeviceInfo device_;
  strategies::BackendChoice backend_;
  std::string label_;
  const Scene* scene_ = nullptr;
  ContextLease context_;
  std::size_t group_ = 256;
  std::size_t node_count_ = 0;
  std::vector<cl_uint> leaf_node_;
  std::vector<cl_int> roots_;
  RefitPlan all_, moving_;
  std::size_t initial_elementary_capacity_ = 0;
  /// Entries each per-pair buffer of the narrow phase may hold (0: no budget planned).
  std::size_t pair_limit_ = 0;
  /// limit_own_bytes's (empty: not set).
  std::function<std::size_t()> own_bytes_limit_;
  /// Reserves `entries` of `entry_bytes` in `buffer`, within pair_limit_.
  void reserve_pairs(Buffer& buffer, std::size_t entries, std::size_t entry_bytes);
  DeviceList out_;
  Buffer keep_;
  Buffer faces_, face_edges_, edges_, masks_, children_, node_face_, max_face_, leaf_node_buffer_, vertex_boxes_, counter_, status_, toi_,
      out_status_, out_toi_, retry_pairs_, retry_status_, retry_toi_, deep_store_;
};

template <class SetArguments>
std::size_t DevicePipeline::fill_list(const char* kernel_name, std::size_t items, DeviceList& list, std::size_t entry_bytes, StageEvents& events,
                                      const char* stage, SetArguments set, std::size_t first) {
  Context& context = *context_;
  cl_kernel kernel = context.kernel(kernel_name);
  const std::size_t room = list.limit != 0 ? list.limit * entry_bytes : static_cast<std::size_t>(-1);
  if (list.limit != 0) list.capacity = std::min(list.capacity, list.limit);
  while (true) {
    list.buffer.reserve(context, std::max<std::size_t>(list.capacity, 1) * entry_bytes, room);
    const cl_uint zero[2] = {0, 0};
    check(clEnqueueWriteBuffer(context.queue(), counter_.get(), CL_FALSE, 0, sizeof(zero), zero, 0, nullptr, nullptr), "clEnqueueWriteBuffer");
    set(kernel, static_cast<cl_uint>(std::min<std::size_t>(list.capacity, 0xFFFFFFFFu)), counter_);
    launch_range(context, kernel, first, items, group_, events.add(stage));
    cl_uint total[2] = {0, 0};
    download(context, counter_, total, 2);
    if (total[1] != 0) {
      if (list.limit != 0) return kListOverflow;
      throw std::runtime_error(label_ + ": the " + stage + " list of one step passed 2^32 entries");
    }
    if (total[0] <= list.capacity) {
      list.count = total[0];
      return total[0];
    }
    if (list.limit != 0 && total[0] > list.limit) return total[0];  // the caller fills a smaller range
    list.capacity = total[0] + total[0] / 4;
    if (list.limit != 0) list.capacity = std::min(list.capacity, list.limit);
  }
}

/// The host's time between the device's profiled stages (kernel launches, blocking reads of counts, waits for
/// events): the step's wall time since `started` less its named stages, added as the stage "launch and wait", so
/// that every millisecond of an OpenCL step is named (issue 36). Call last in a step.
void add_launch_and_wait(strategies::StepResult& result, std::chrono::steady_clock::time_point started);

}  // namespace ccd::opencl
