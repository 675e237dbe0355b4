#include "strategies/apccd/opencl/apccd_opencl.hpp"

#include "strategies/face_shape.hpp"
#include "strategies/opencl/pipeline.hpp"

#include <chrono>
#include <stdexcept>

namespace ccd::strategies {
namespace {

using opencl::Buffer;
using opencl::check;
using opencl::DeviceList;
using opencl::download;
using opencl::launch;
using opencl::set_arguments;
using opencl::upload;

/// The pending list's hash table is rebuilt larger once it would be more than half full (linear probing stays
/// short below that).
constexpr std::size_t kTableLoadInverse = 2;
/// Lists are indexed with 32-bit work-item ids and counters in the kernels.
constexpr std::size_t kMaxListEntries = 0xFFFFFFFFull;

class ApccdOpenCl final : public Strategy {
 public:
  ApccdOpenCl(const ApccdSettings& settings, opencl::NarrowPhaseChoice narrow_phase, opencl::DeviceInfo device, const BackendChoice& backend)
      : settings_(settings), pipeline_(std::move(narrow_phase), std::move(device), backend, "apccd:backend=opencl") {}

  std::vector<std::pair<std::string, std::string>> provenance() const override { return pipeline_.provenance(); }

  std::string name() const override {
    const opencl::NarrowPhaseChoice& narrow = pipeline_.narrow_phase();
    return apccd_name(settings_, narrow.host->name()) + pipeline_.backend().resolved(pipeline_.device().name, narrow.conservative());
  }

  void prepare() override { pipeline_.prepare(); }

  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    scene_ = &scene;
    pipeline_.init(scene, first_frame);
    memory_budget_ = pipeline_.budget_bytes();
    pipeline_.limit_own_bytes([this] { return budget_left_to_pipeline(); });
    session_.init(settings_, scene, first_frame);
    history_ = ProximityHistory(settings_.history);
    opencl::Context& context = pipeline_.context();
    const MeshTopology& topology = scene.topology();
    num_vertices_ = topology.num_vertices();
    objects_with_pairs_ = !scene.collidable_pairs().empty();
    pipeline_.make_queries(self_queries_, true, false, false);
    if (objects_with_pairs_) pipeline_.make_queries(pair_queries_, false, true, !settings_.fresh_object_pairs);
    std::vector<cl_uint> vertex_object(num_vertices_);
    std::vector<cl_int> face_root(topology.num_faces(), -1);
    for (ObjectId id = 0; id < scene.objects().size(); ++id) {
      const SceneObject& object = scene.object(id);
      for (std::size_t i = 0; i < object.num_vertices; ++i) vertex_object[object.first_vertex + i] = static_cast<cl_uint>(id);
      if (!object.self_collision) continue;
      for (std::size_t i = 0; i < object.num_faces; ++i) face_root[object.first_face + i] = pipeline_.roots()[id];
    }
    upload(context, vertex_object_, vertex_object.data(), vertex_object.size());
    upload(context, face_root_, face_root.data(), face_root.size());
    // Both sets of trees are fitted over frame 0 (static objects stay so): the session's (each object's frame) and,
    // for object_pairs=fresh, the world-frame ones.
    const std::size_t box_bytes = std::max<std::size_t>(pipeline_.node_count(), 1) * 6 * sizeof(double);
    session_boxes_.reserve(context, box_bytes);
    if (num_vertices_ == 0) throw std::invalid_argument("apccd:backend=opencl: the scene has no vertices");
    positions_.reset(context, first_frame);
    pipeline_.refit(pipeline_.all_nodes(), positions_.x0(), positions_.x1(), scene.thickness() / 2, nullptr, session_boxes_, nullptr);
    if (objects_with_pairs_ && settings_.fresh_object_pairs) {
      world_boxes_.reserve(context, box_bytes);
      pipeline_.refit(pipeline_.all_nodes(), positions_.x0(), positions_.x1(), scene.thickness() / 2, nullptr, world_boxes_, nullptr);
    }
    for (Buffer* relative : {&relative_[0], &relative_[1], &anchor_})
      relative->reserve(context, std::max<std::size_t>(num_vertices_, 1) * 3 * sizeof(double));
    budget_.reserve(context, std::max<std::size_t>(num_vertices_, 1) * sizeof(double));
    dangling_.reserve(context, std::max<std::size_t>(num_vertices_, 1));
    face_boxes_.reserve(context, std::max<std::size_t>(topology.num_faces(), 1) * 6 * sizeof(double));
    counter_.reserve(context, 2 * sizeof(cl_uint));
    pending_.count = 0;
    table_bits_ = 0;
    table_builds_ = 0;
    table_valid_ = false;
    context.finish();
    // The buffers every step keeps, before any list: a budget below them is refused here, as full's is.
    if (const std::size_t fixed = device_bytes(); fixed > memory_budget_) {
      throw std::invalid_argument(pipeline_.label() + ": memory=" + pipeline_.backend().memory.text() + " (" + std::to_string(memory_budget_) +
                                  " bytes) is below what this scene's buffers need before any step: " + std::to_string(fixed) +
                                  " bytes; give more memory=");
    }
  }

  StepResult step(const StepView& step, bool audit) override {
    const auto started = std::chrono::steady_clock::now();
    StepResult result;
    opencl::StageEvents events;
    opencl::Context& context = pipeline_.context();
    const double half = scene_->thickness() / 2;
    positions_.begin(context, step, events);
    const Buffer& x0 = positions_.x0();
    const Buffer& x1 = positions_.x1();

    const bool session_start = session_.starts();
    std::size_t dangling_vertices = 0, dangling_triangles = 0;
    double relative_motion = 0;
    {
      ScopedStageTimer timer(result.stages, "update (host)");
      session_.update_centroids(step);
      relative_motion = session_.relative_motion(step);
    }
    object_frame(x0, session_.centroid0(), 0, events);
    object_frame(x1, session_.centroid1(), 1, events);
    if (session_start) {
      start_session(step, result, events);
    } else {
      dangling_vertices = collect_dangling(events);
      dangling_triangles = dangling_faces_.count;
      partial_traversal(events);
    }
    const DeviceList* across = object_pairs(x0, x1, half, events);
    // The front end: candidates whose fresh swept boxes overlap.
    const bool box_filter = settings_.front_end != FrontEnd::off;
    if (box_filter) {
      cl_kernel kernel = context.kernel("face_boxes");
      const std::size_t faces = scene_->topology().num_faces();
      set_arguments(kernel, static_cast<cl_uint>(faces), pipeline_.faces().get(), x0.get(), x1.get(), half, face_boxes_.get());
      launch(context, kernel, faces, pipeline_.group(), events.add("front end"));
    }
    const std::size_t across_count = across != nullptr ? across->count : 0;
    if (pending_.count + across_count > kMaxListEntries) {
      throw std::runtime_error("apccd:backend=opencl: " + std::to_string(pending_.count + across_count) +
                               " pending and object pairs in one step; the kernels index at most 2^32 - 1");
    }
    const cl_mem across_memory = across != nullptr ? across->buffer.get() : nullptr;
    if (admissible_.capacity == 0) admissible_.capacity = pipeline_.list_start(std::max<std::size_t>(4 * scene_->topology().num_faces(), 1024));
    const std::size_t admissible =
        pipeline_.fill_list("admit", pending_.count + across_count, admissible_, sizeof(cl_uint2), events, "front end",
                            [&](cl_kernel kernel, cl_uint capacity, const Buffer& counter) {
                              const cl_uchar check_boxes = box_filter ? 1 : 0;
                              set_arguments(kernel, static_cast<cl_uint>(pending_.count), pending_.buffer.get(), static_cast<cl_uint>(across_count),
                                            across_memory, face_boxes_.get(), check_boxes, capacity, counter.get(), admissible_.buffer.get());
                            });
    // The back end: elementary pairs by the masks and the primitive box test, the distance heuristic, the narrow phase.
    pipeline_.vertex_boxes(x0, x1, events);
    const std::size_t elementary = pipeline_.expand(admissible_.buffer, admissible, elementary_, events);
    const DeviceList* tested = &elementary_;
    if (settings_.front_end == FrontEnd::on) {
      pipeline_.filter(elementary_.buffer, elementary, x0, x1, tested_, events);
      tested = &tested_;
    }
    const std::size_t tests = tested->count;
    pipeline_.back_end(tested->buffer, tests, step, x0, x1, result, events);
    for (const auto& [stage, milliseconds] : events.collect()) result.stages.add(stage, milliseconds);
    std::size_t history_catches = 0;
    if (audit || settings_.history != HistoryMode::off) {
      TestedPairs pairs = pipeline_.tested_pairs(tested->buffer, tests);
      if (settings_.history != HistoryMode::off) {
        ScopedStageTimer timer(result.stages, "history (host)");
        history_catches = history_.apply(scene_->topology(), step.x1, pairs, result.collisions);
      }
      if (audit) result.tested = std::move(pairs);
    }
    positions_.finish(step);
    result.counters.candidate_triangle_pairs = admissible;
    result.counters.elementary_tests = tests;
    const std::size_t device = checked_device_bytes(step);
    result.counters.device_bytes = device;
    result.counters.history_bytes = history_.bytes();
    result.counters.kept_bytes = history_.bytes();
    std::vector<std::pair<std::string, double>> extra = {{"session_start", session_start ? 1.0 : 0.0},
                                                         {"nf", static_cast<double>(session_.nf())},
                                                         {"pending_pairs", static_cast<double>(pending_.count)},
                                                         {"dangling_vertices", static_cast<double>(dangling_vertices)},
                                                         {"dangling_triangles", static_cast<double>(dangling_triangles)},
                                                         {"history_pairs", static_cast<double>(history_.pairs())},
                                                         {"history_catches", static_cast<double>(history_catches)},
                                                         {"history_table_bytes", static_cast<double>(history_.bytes())},
                                                         {"distance_filtered", static_cast<double>(elementary - tests)},
                                                         {"device_bytes", static_cast<double>(device)},
                                                         {kDeviceBudgetCounter, static_cast<double>(memory_budget_)},
                                                         {"pending_table_builds", static_cast<double>(table_builds_)},
                                                         {"admissible_pairs", static_cast<double>(admissible)},
                                                         {"object_pair_candidates", static_cast<double>(across_count)},
                                                         {"relative_motion", relative_motion}};
    extra.insert(extra.end(), result.counters.extra.begin(), result.counters.extra.end());
    result.counters.extra = std::move(extra);
    // Face-shape pairs on the host, with the host's narrow phase (face_shape.hpp), as the CPU backend does.
    run_face_shape_stage(result, *scene_, step, *pipeline_.narrow_phase().host, audit);
    add_session_end_counters(session_.advance(dangling_vertices, admissible, pending_.count), result.counters.extra);
    opencl::add_launch_and_wait(result, started);
    return result;
  }

 private:
  /// The device memory this step's lists hold, refused (std::runtime_error) over memory=.
  std::size_t checked_device_bytes(const StepView& step) const {
    const std::size_t device = device_bytes();
    if (device > memory_budget_) {
      // apccd's lists carry over from step to step (pending pairs, sessions): it does not run a step in pieces.
      throw std::runtime_error(pipeline_.label() + ": step " + std::to_string(step.index) + " needed " + std::to_string(device) +
                               " bytes of device memory, more than memory=" + pipeline_.backend().memory.text() + " allows (" +
                               std::to_string(memory_budget_) +
                               " bytes): apccd holds a step's lists whole; full:backend=opencl runs such a step in chunks, or give a larger memory=");
    }
    return device;
  }

  /// Pairs across objects, every step: a fresh traversal of the world boxes, or of the session's boxes moved by each
  /// object pair's offset; nullptr when the scene has no object pairs.
  const DeviceList* object_pairs(const Buffer& x0, const Buffer& x1, double half, opencl::StageEvents& events) {
    if (!objects_with_pairs_) return nullptr;
    if (settings_.fresh_object_pairs) {
      pipeline_.refit(pipeline_.moving_nodes(), x0, x1, half, nullptr, world_boxes_, &events);
      pipeline_.traverse(pair_queries_, world_boxes_, nullptr, across_, events, "object pairs");
    } else {
      std::vector<double>& offsets = host_offsets_;  // read by the device after this call returns
      offsets.clear();
      for (const auto& [a, b] : scene_->collidable_pairs()) {
        const Box3 offset = session_.pair_offset(a, b);
        for (int k = 0; k < 3; ++k) offsets.push_back(offset.min()[k]);
        for (int k = 0; k < 3; ++k) offsets.push_back(offset.max()[k]);
      }
      upload(pipeline_.context(), offsets_, offsets.data(), offsets.size(), events.add("object pairs"));
      pipeline_.traverse(pair_queries_, session_boxes_, &offsets_, across_, events, "object pairs");
    }
    return &across_;
  }

  /// Positions relative to the objects' centroids (uploaded, as the host summed them).
  /// Host data uploaded without waiting (host_centroids_, host_budget_) is rewritten only in a later step, after
  /// this step's blocking reads have drained the in-order queue.
  void object_frame(const Buffer& x, const std::vector<Vec3>& centroids, int end, opencl::StageEvents& events) {
    opencl::Context& context = pipeline_.context();
    std::vector<double>& flat = host_centroids_[end];
    flat.clear();
    for (const Vec3& c : centroids) flat.insert(flat.end(), {c.x(), c.y(), c.z()});
    upload(context, centroids_[end], flat.data(), flat.size(), events.add("update"));
    cl_kernel kernel = context.kernel("object_frame");
    set_arguments(kernel, static_cast<cl_uint>(num_vertices_), x.get(), vertex_object_.get(), centroids_[end].get(), relative_[end].get());
    launch(context, kernel, num_vertices_, pipeline_.group(), events.add("update"));
  }

  /// A session's first frame: the host's budgets (the CPU backend's code and order), the inflated refit of every
  /// moving object's session tree, and the full self traversal into the pending list.
  void start_session(const StepView& step, StepResult& result, opencl::StageEvents& events) {
    opencl::Context& context = pipeline_.context();
    {
      ScopedStageTimer timer(result.stages, "update (host)");
      session_.relative_positions(step, host_relative0_, host_relative1_);
      session_.start(host_relative0_, host_relative1_, host_budget_);
    }
    upload(context, budget_, host_budget_.data(), host_budget_.size(), events.add("update"));
    check(clEnqueueCopyBuffer(context.queue(), relative_[1].get(), anchor_.get(), 0, 0, num_vertices_ * 3 * sizeof(double), 0, nullptr,
                              events.add("update")),
          "clEnqueueCopyBuffer");
    pipeline_.refit(pipeline_.moving_nodes(), relative_[0], relative_[1], scene_->thickness() / 2, &budget_, session_boxes_, &events);
    pipeline_.traverse(self_queries_, session_boxes_, nullptr, pending_, events, "traversal");
    table_valid_ = false;
  }

  /// Dangling vertices (counted) and the list of dangling triangles.
  std::size_t collect_dangling(opencl::StageEvents& events) {
    opencl::Context& context = pipeline_.context();
    const cl_uint zero[2] = {0, 0};
    check(clEnqueueWriteBuffer(context.queue(), counter_.get(), CL_FALSE, 0, sizeof(zero), zero, 0, nullptr, nullptr), "clEnqueueWriteBuffer");
    cl_kernel kernel = context.kernel("dangling_vertices");
    set_arguments(kernel, static_cast<cl_uint>(num_vertices_), relative_[0].get(), relative_[1].get(), anchor_.get(), budget_.get(), dangling_.get(),
                  counter_.get());
    launch(context, kernel, num_vertices_, pipeline_.group(), events.add("dangling collection"));
    cl_uint count[2] = {0, 0};
    download(context, counter_, count, 2);
    const std::size_t faces = scene_->topology().num_faces();
    if (dangling_faces_.capacity == 0) dangling_faces_.capacity = pipeline_.list_start(faces);
    if (count[0] == 0) {
      dangling_faces_.count = 0;
      return 0;
    }
    pipeline_.fill_list("dangling_faces", faces, dangling_faces_, sizeof(cl_uint), events, "dangling collection",
                        [&](cl_kernel list, cl_uint capacity, const Buffer& counter) {
                          set_arguments(list, static_cast<cl_uint>(faces), pipeline_.faces().get(), dangling_.get(), capacity, counter.get(),
                                        dangling_faces_.buffer.get());
                        });
    return count[0];
  }

  /// Enlarges the dangling triangles' leaves to their fresh boxes, refits the levels above, then finds every face
  /// of a self-colliding object whose leaf overlaps a dangling triangle's fresh box; new pairs join the pending list.
  void partial_traversal(opencl::StageEvents& events) {
    const std::size_t count = dangling_faces_.count;
    if (count == 0) return;
    opencl::Context& context = pipeline_.context();
    fresh_boxes_.reserve(context, count * 6 * sizeof(double));
    cl_kernel enlarge = context.kernel("enlarge_leaves");
    set_arguments(enlarge, static_cast<cl_uint>(count), dangling_faces_.buffer.get(), pipeline_.leaf_node_buffer().get(), pipeline_.faces().get(),
                  relative_[0].get(), relative_[1].get(), scene_->thickness() / 2, session_boxes_.get(), fresh_boxes_.get());
    launch(context, enlarge, count, pipeline_.group(), events.add("partial traversal"));
    pipeline_.refit_levels(pipeline_.moving_nodes(), session_boxes_, &events);
    if (found_.capacity == 0) found_.capacity = pipeline_.list_start(std::max<std::size_t>(4 * count, 1024));
    const std::size_t found = pipeline_.fill_list(
        "partial_traverse", count, found_, sizeof(cl_uint2), events, "partial traversal",
        [&](cl_kernel kernel, cl_uint capacity, const Buffer& counter) {
          set_arguments(kernel, static_cast<cl_uint>(count), dangling_faces_.buffer.get(), fresh_boxes_.get(), face_root_.get(), session_boxes_.get(),
                        pipeline_.children().get(), pipeline_.node_face().get(), capacity, counter.get(), found_.buffer.get());
        });
    if (found == 0) return;
    // The table holds the pending list; it is (re)built when missing or when the new pairs could fill it past half.
    const std::size_t most = pending_.count + found;
    if (most > kMaxListEntries) {
      throw std::runtime_error("apccd:backend=opencl: a pending list of " + std::to_string(most) + " pairs; the kernels index at most 2^32 - 1");
    }
    if (!table_valid_ || kTableLoadInverse * most > (std::size_t{1} << table_bits_)) {
      table_bits_ = 4;
      // Room for the list to double before the next rebuild; with list_start, lists grow from small and the table
      // is rebuilt at every growth too.
      const std::size_t headroom = pipeline_.backend().list_start != 0 ? 1 : 2;
      while ((std::size_t{1} << table_bits_) < kTableLoadInverse * most * headroom) ++table_bits_;
      const std::size_t slots = std::size_t{1} << table_bits_;
      table_.reserve(context, slots * sizeof(cl_ulong));
      ++table_builds_;
      const cl_ulong empty = opencl::kEmptyPendingKey;
      check(clEnqueueFillBuffer(context.queue(), table_.get(), &empty, sizeof(empty), 0, slots * sizeof(cl_ulong), 0, nullptr,
                                events.add("partial traversal")),
            "clEnqueueFillBuffer");
      insert(pending_.buffer, pending_.count, false, events);
      table_valid_ = true;
    }
    pending_.buffer.reserve_keeping(context, most * sizeof(cl_uint2), pending_.count * sizeof(cl_uint2));
    pending_.capacity = std::max(pending_.capacity, pending_.buffer.bytes() / sizeof(cl_uint2));
    pending_.count += insert(found_.buffer, found, true, events);
  }

  /// Inserts `count` pairs of `pairs` into the table; with `append`, those not there yet also go to the end of the
  /// pending list. Returns how many were new (with append).
  std::size_t insert(const Buffer& pairs, std::size_t count, bool append, opencl::StageEvents& events) {
    if (count == 0) return 0;
    opencl::Context& context = pipeline_.context();
    const cl_uint zero[2] = {0, 0};
    check(clEnqueueWriteBuffer(context.queue(), counter_.get(), CL_FALSE, 0, sizeof(zero), zero, 0, nullptr, nullptr), "clEnqueueWriteBuffer");
    cl_kernel kernel = context.kernel("pending_insert");
    const cl_uchar append_flag = append ? 1 : 0;
    set_arguments(kernel, static_cast<cl_uint>(count), pairs.get(), table_.get(), static_cast<cl_uint>(table_bits_), append_flag,
                  pending_.buffer.get(), static_cast<cl_uint>(pending_.count), counter_.get());
    launch(context, kernel, count, pipeline_.group(), events.add("partial traversal"));
    cl_uint added[2] = {0, 0};
    download(context, counter_, added, 2);
    return added[0];
  }

  /// What memory= leaves the pipeline's own buffers over every other buffer of the step: the deep pass's store stays
  /// within it (apccd holds its step whole, so the budget binds the step's peak).
  std::size_t budget_left_to_pipeline() const {
    const std::size_t others = device_bytes() - pipeline_.bytes();
    return memory_budget_ > others ? memory_budget_ - others : 0;
  }

  std::size_t device_bytes() const {
    std::size_t total = pipeline_.bytes() + positions_.bytes() + self_queries_.bytes() + pair_queries_.bytes();
    for (const Buffer* b : {&relative_[0],
                            &relative_[1],
                            &anchor_,
                            &budget_,
                            &dangling_,
                            &session_boxes_,
                            &world_boxes_,
                            &face_boxes_,
                            &fresh_boxes_,
                            &centroids_[0],
                            &centroids_[1],
                            &vertex_object_,
                            &face_root_,
                            &offsets_,
                            &table_,
                            &counter_,
                            &pending_.buffer,
                            &across_.buffer,
                            &admissible_.buffer,
                            &elementary_.buffer,
                            &tested_.buffer,
                            &found_.buffer,
                            &dangling_faces_.buffer}) {
      total += b->bytes();
    }
    return total;
  }

  ApccdSettings settings_;
  opencl::DevicePipeline pipeline_;
  std::uint64_t memory_budget_ = 0;  // memory= on this device, in bytes
  ApccdSession session_;
  ProximityHistory history_;
  const Scene* scene_ = nullptr;
  std::size_t num_vertices_ = 0;
  bool objects_with_pairs_ = false;
  opencl::DevicePositions positions_;
  opencl::Queries self_queries_, pair_queries_;
  std::vector<Vec3> host_relative0_, host_relative1_;
  std::vector<double> host_budget_;
  std::vector<double> host_centroids_[2];
  std::vector<double> host_offsets_;
  std::size_t table_bits_ = 0;
  /// How often the table was built (counter pending_table_builds).
  std::size_t table_builds_ = 0;
  bool table_valid_ = false;
  Buffer relative_[2], anchor_, budget_, dangling_, session_boxes_, world_boxes_, face_boxes_, fresh_boxes_, centroids_[2], vertex_object_,
      face_root_, offsets_, table_, counter_;
  DeviceList pending_, across_, admissible_, elementary_, tested_, found_, dangling_faces_;
};

}  // namespace

std::unique_ptr<Strategy> make_apccd_opencl(const ApccdSettings& settings, std::unique_ptr<narrowphase::NarrowPhase> narrow_phase,
                                            const BackendChoice& backend) {
  opencl::NarrowPhaseChoice narrow = opencl::choose_narrow_phase("apccd", std::move(narrow_phase));
  opencl::DeviceInfo device = opencl::choose_checked_device("apccd", backend.device, true);
  return std::make_unique<ApccdOpenCl>(settings, std::move(narrow), std::move(device), backend);
}

}  // namespace ccd::strategies
