#include "strategies/opencl/pipeline.hpp"

#include "core/assignment.hpp"
#include "strategies/bvh/bvh.hpp"
#include "strategies/elementary_tests.hpp"
#include "strategies/narrowphase_registry.hpp"
#include "strategies/opencl/self_test.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdio>

namespace ccd::opencl {
namespace {

/// Work-group size of the kernels that reserve list space per group (CCD_GROUP_SIZE): 256, or the device's
/// largest power of two below that.
std::size_t group_size_for(const DeviceInfo& device) {
  std::size_t group = 256;
  while (group > device.max_work_group_size && group > 1) group /= 2;
  return group;
}

/// The second device pass gives up after this many iterations: the queries that cloth-funnel hands back finish
/// within it, side by side; what is left runs to the cap.
constexpr long kSecondPassIterations = 4000;
/// Fewest kept pairs per chunk of the collision set's assembly (4,096 before issue 36; on the H100 machine 512
/// took the large suite's step from 0.76 to 0.56 ms in this stage, and made no difference on rod-twist's 4,944).
constexpr std::size_t kOutputChunk = 512;
/// Largest level that the refit leaves to one work group with the levels around it (a few nodes per work item):
/// the device finishes such a level in less time than it waits between two launches (issue 36: a median-split
/// tree's levels within 10 of the root are that small, more than half of an 80k-face tree's; reports/opencl/step).
constexpr std::size_t kLevelsInGroupNodes = 1024;
/// Depth the traversal kernel's stack holds (CCD_TRAVERSAL_STACK): the hierarchies split at the median, so a tree
/// of n faces is ceil(log2 n) + 1 deep; init refuses a deeper tree before any launch.
constexpr std::size_t kTraversalStack = 64;

/// "0x1p-50": a double as a C hexadecimal literal, exact.
std::string hexadecimal(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%a", value);
  return text;
}

EdgeEdgePair edge_pair(const cl_uint4& p) { return {Edge{p.s[0], p.s[1]}, Edge{p.s[2], p.s[3]}}; }

}  // namespace

DeviceInfo choose_checked_device(const std::string& strategy, const std::string& selector, bool int64_atomics) {
  if (names_several_devices(selector)) {
    throw std::invalid_argument(strategy + ":backend=opencl: device=" + selector + ": " + strategy +
                                " runs on one device (full:backend=opencl runs a step over several)");
  }
  DeviceInfo device = choose_device(list_devices(), selector);
  require_double_precision(device);
  if (int64_atomics && !device.int64_atomics) {
    throw std::invalid_argument(strategy + ":backend=opencl: device " + std::to_string(device.index) + " (" + device.name +
                                ") has no 64-bit atomics (cl_khr_int64_base_atomics), which apccd's pending list needs; "
                                "full:backend=opencl runs there");
  }
  return device;
}

std::vector<DeviceInfo> choose_checked_devices(const std::string& strategy, const std::string& selector) {
  std::vector<DeviceInfo> devices = choose_devices(list_devices(), selector);
  for (const DeviceInfo& device : devices) {
    try {
      require_double_precision(device);
    } catch (const std::invalid_argument& refusal) {
      throw std::invalid_argument(strategy + ":backend=opencl:device=" + selector + ": " + refusal.what());
    }
  }
  return devices;
}

void refuse_host_narrow_phase(const std::string& strategy, const std::string& name) {
  std::string runs;
  for (const narrowphase::NarrowPhaseEntry& entry : narrowphase::narrow_phases()) {
    const auto backends = narrowphase::narrow_phase_backends(entry);
    if (std::find(backends.begin(), backends.end(), "opencl") != backends.end()) runs += (runs.empty() ? "" : ", ") + entry.name;
  }
  throw std::invalid_argument(strategy + ":backend=opencl runs the narrow phases " + runs + ", not " + name);
}

NarrowPhaseChoice choose_narrow_phase(const std::string& strategy, std::unique_ptr<narrowphase::NarrowPhase> host) {
  const std::optional<narrowphase::DeviceForm> form = host->device_form();
  if (!form) refuse_host_narrow_phase(strategy, host->name());
  return {std::move(host), *form};
}

std::string kernel_defines(std::size_t group_size, long sub_boxes) {
  return "-DCCD_GROUP_SIZE=" + std::to_string(group_size) + " -DCCD_DEVICE_SUB_BOXES=" + std::to_string(sub_boxes) +
         " -DCCD_BOX_ROUNDING_MARGIN=" + hexadecimal(bvh::kBoxRoundingMargin) + " -DCCD_TRAVERSAL_STACK=" + std::to_string(kTraversalStack) +
         " -DCCD_VERTEX_FACE=" + std::to_string(kVertexFacePair) + "u -DCCD_EMPTY_KEY=" + std::to_string(kEmptyPendingKey) + "UL";
}

void DevicePositions::reset(Context& context, std::span<const Vec3> frame) {
  upload(context, x_[0], frame.data()->data(), 3 * frame.size());
  upload(context, x_[1], frame.data()->data(), 3 * frame.size());
  current_ = 0;
  last_step_ = static_cast<std::size_t>(-1);
}

void DevicePositions::begin(Context& context, const StepView& step, StageEvents& events) {
  if (step.index != last_step_ + 1) upload(context, x_[current_], step.x0.data()->data(), 3 * step.x0.size(), events.add("upload"));
  upload(context, x_[1 - current_], step.x1.data()->data(), 3 * step.x1.size(), events.add("upload"));
}

void DevicePositions::finish(const StepView& step) {
  current_ = 1 - current_;
  last_step_ = step.index;
}

DevicePipeline::DevicePipeline(NarrowPhaseChoice narrow_phase, DeviceInfo device, strategies::BackendChoice backend, std::string label)
    : narrow_phase_(std::move(narrow_phase)), device_(std::move(device)), backend_(std::move(backend)), label_(std::move(label)) {}

void DevicePipeline::prepare() {
  if (!context_) {
    group_ = group_size_for(device_);
    context_ = lease_context(device_, kernel_defines(group_, backend_.sub_boxes));
  }
  if (!context_->arithmetic_checked) {  // (again, after a check that threw: a refused device stays refused)
    check_device_arithmetic(*context_);
    context_->arithmetic_checked = true;
  }
  // The deep pass's program too, built and checked here so that no step's time holds a build: on an H200 its first
  // build took 12.8 s (NVIDIA's own cache keeps it for later processes), inside the first step whose queries overflowed.
  if (narrow_phase_.conservative() && !context_->deep_pass_checked) {
    check_deep_pass_arithmetic(*context_, deep_sub_boxes());
    context_->deep_pass_checked = true;
  }
}

void DevicePipeline::init(const Scene& scene, std::span<const Vec3> first_frame) {
  scene_ = &scene;
  prepare();
  const MeshTopology& topology = scene.topology();
  const std::size_t faces = topology.num_faces();
  std::vector<cl_uint> face_corners(3 * faces), face_edges(3 * faces);
  for (FaceId f = 0; f < faces; ++f) {
    for (int k = 0; k < 3; ++k) {
      face_corners[3 * f + static_cast<std::size_t>(k)] = topology.face(f)[static_cast<std::size_t>(k)];
      face_edges[3 * f + static_cast<std::size_t>(k)] = topology.face_edges(f)[static_cast<std::size_t>(k)];
    }
  }
  std::vector<cl_uint2> edges(topology.num_edges());
  for (EdgeId e = 0; e < edges.size(); ++e) edges[e] = {{topology.edge(e).v0, topology.edge(e).v1}};
  const std::vector<AssignmentMask> masks = assign_primitives(topology);
  build_hierarchies(scene, first_frame);
  upload(*context_, faces_, face_corners.data(), face_corners.size());
  upload(*context_, face_edges_, face_edges.data(), face_edges.size());
  upload(*context_, edges_, edges.data(), edges.size());
  upload(*context_, masks_, masks.data(), masks.size());
  counter_.reserve(*context_, 2 * sizeof(cl_uint));
  initial_elementary_capacity_ = list_start(16 * std::max<std::size_t>(faces, 256));
  out_.capacity = list_start(1024);
  context_->finish();
}

void DevicePipeline::build_hierarchies(const Scene& scene, std::span<const Vec3> first_frame) {
  std::vector<cl_int2> children;
  std::vector<cl_uint> node_face, depth;
  leaf_node_.assign(scene.topology().num_faces(), 0);
  roots_.assign(scene.objects().size(), -1);
  std::vector<bool> moving_node;
  for (ObjectId id = 0; id < scene.objects().size(); ++id) {
    const SceneObject& object = scene.object(id);
    bvh::TriangleBvh tree;
    tree.build(scene.topology(), object.first_face, object.num_faces, first_frame);
    if (tree.empty()) continue;
    const auto base = static_cast<cl_int>(children.size());
    roots_[id] = base;
    const auto& nodes = tree.nodes();
    std::vector<cl_uint> local_depth(nodes.size(), 0);
    for (std::size_t n = 0; n < nodes.size(); ++n) {  // children follow their parent in build order
      if (!nodes[n].is_leaf()) {
        local_depth[static_cast<std::size_t>(nodes[n].left)] = local_depth[n] + 1;
        local_depth[static_cast<std::size_t>(nodes[n].right)] = local_depth[n] + 1;
      }
    }
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      const auto& node = nodes[n];
      children.push_back(node.is_leaf() ? cl_int2{{-1, -1}} : cl_int2{{node.left + base, node.right + base}});
      node_face.push_back(node.is_leaf() ? node.face : 0);
      depth.push_back(local_depth[n]);
      moving_node.push_back(object.kind != ObjectKind::static_object);
      if (node.is_leaf()) leaf_node_[node.face] = static_cast<cl_uint>(base) + static_cast<cl_uint>(n);
      if (local_depth[n] + 1 >= kTraversalStack) {
        throw std::invalid_argument(label_ + ": object " + object.name + "'s hierarchy is deeper than the " + std::to_string(kTraversalStack) +
                                    " levels its traversal stack holds");
      }
    }
  }
  node_count_ = children.size();
  // The largest face of each subtree, for self queries' pruning (kernels/full.cl): children follow their parent.
  std::vector<cl_uint> max_face(node_face);
  for (std::size_t n = node_count_; n-- > 0;) {
    if (children[n].s[0] >= 0) {
      max_face[n] = std::max(max_face[static_cast<std::size_t>(children[n].s[0])], max_face[static_cast<std::size_t>(children[n].s[1])]);
    }
  }
  // Leaves, and internal nodes grouped by depth, deepest first (children before parents).
  cl_uint max_depth = 0;
  for (cl_uint d : depth) max_depth = std::max(max_depth, d);
  std::vector<cl_uint> leaves_all, leaves_moving;
  std::vector<std::vector<cl_uint>> by_depth(max_depth + 1);
  for (std::size_t n = 0; n < node_count_; ++n) {
    if (children[n].s[0] < 0) {
      leaves_all.push_back(static_cast<cl_uint>(n));
      if (moving_node[n]) leaves_moving.push_back(static_cast<cl_uint>(n));
    } else {
      by_depth[depth[n]].push_back(static_cast<cl_uint>(n));
    }
  }
  std::vector<cl_uint> levels_all, levels_moving;
  all_.level_offsets.assign(1, 0);
  moving_.level_offsets.assign(1, 0);
  for (std::size_t d = by_depth.size(); d-- > 0;) {
    for (cl_uint n : by_depth[d]) {
      levels_all.push_back(n);
      if (moving_node[n]) levels_moving.push_back(n);
    }
    all_.level_offsets.push_back(levels_all.size());
    moving_.level_offsets.push_back(levels_moving.size());
  }
  Context& context = *context_;
  upload(context, children_, children.data(), children.size());
  upload(context, node_face_, node_face.data(), node_face.size());
  upload(context, max_face_, max_face.data(), max_face.size());
  upload(context, leaf_node_buffer_, leaf_node_.data(), leaf_node_.size());
  all_.leaf_count = leaves_all.size();
  moving_.leaf_count = leaves_moving.size();
  upload(context, all_.leaves, leaves_all.data(), leaves_all.size());
  upload(context, moving_.leaves, leaves_moving.data(), leaves_moving.size());
  upload(context, all_.levels, levels_all.data(), levels_all.size());
  upload(context, moving_.levels, levels_moving.data(), levels_moving.size());
  // (Uploads don't wait: what they read lives until the finish below.)
  const std::vector<cl_uint> all_offsets(all_.level_offsets.begin(), all_.level_offsets.end()),
      moving_offsets(moving_.level_offsets.begin(), moving_.level_offsets.end());
  upload(context, all_.offsets, all_offsets.data(), all_offsets.size());
  upload(context, moving_.offsets, moving_offsets.data(), moving_offsets.size());
  context.finish();
}

void DevicePipeline::refit(const RefitPlan& plan, const Buffer& x0, const Buffer& x1, double inflation, const Buffer* budget,
                           const Buffer& node_boxes, StageEvents* events) {
  Context& context = *context_;
  cl_kernel boxes = context.kernel("leaf_boxes");
  const cl_mem budget_memory = budget != nullptr ? budget->get() : nullptr;
  const cl_uchar has_budget = budget != nullptr ? 1 : 0;
  set_arguments(boxes, static_cast<cl_uint>(plan.leaf_count), plan.leaves.get(), node_face_.get(), faces_.get(), x0.get(), x1.get(), inflation,
                has_budget, budget_memory, node_boxes.get());
  launch(context, boxes, plan.leaf_count, group_, events != nullptr ? events->add("boxes") : nullptr);
  refit_levels(plan, node_boxes, events);
}

void DevicePipeline::refit_levels(const RefitPlan& plan, const Buffer& node_boxes, StageEvents* events) {
  Context& context = *context_;
  cl_kernel level = context.kernel("refit_level");
  cl_kernel in_group = context.kernel("refit_levels_in_group");
  const std::vector<std::size_t>& offsets = plan.level_offsets;
  if (offsets.empty()) return;
  // A level of more than kLevelsInGroupNodes nodes is a launch of its own; each run of smaller levels between them
  // is one launch of one work group, which refits them in order with a barrier between levels. A run without a
  // node (the deepest level holds leaves only, and a plan without moving objects is empty) launches nothing.
  std::size_t run = 0;  // first level of the run of small levels not yet launched
  auto launch_run = [&](std::size_t end) {
    if (offsets[end] == offsets[run]) return;
    set_arguments(in_group, static_cast<cl_uint>(run), static_cast<cl_uint>(end), plan.offsets.get(), plan.levels.get(), children_.get(),
                  node_boxes.get());
    launch(context, in_group, group_, group_, events != nullptr ? events->add("refit") : nullptr);
  };
  for (std::size_t i = 0; i + 1 < offsets.size(); ++i) {
    const std::size_t count = offsets[i + 1] - offsets[i];
    if (count <= kLevelsInGroupNodes) continue;
    launch_run(i);
    run = i + 1;
    set_arguments(level, static_cast<cl_uint>(count), static_cast<cl_uint>(offsets[i]), plan.levels.get(), children_.get(), node_boxes.get());
    launch(context, level, count, group_, events != nullptr ? events->add("refit") : nullptr);
  }
  launch_run(offsets.size() - 1);
}

std::size_t DevicePipeline::traverse(const Queries& queries, const Buffer& node_boxes, const Buffer* offsets, DeviceList& out, StageEvents& events,
                                     const char* stage, std::size_t first, std::size_t count) {
  if (out.capacity == 0) out.capacity = list_start(std::max<std::size_t>(4 * scene_->topology().num_faces(), 1024));
  const cl_mem offset_memory = offsets != nullptr ? offsets->get() : nullptr;
  const std::size_t end = first + std::min(count, queries.count - first);
  return fill_list(
      "traverse", end - first, out, sizeof(cl_uint2), events, stage,
      [&](cl_kernel kernel, cl_uint capacity, const Buffer& counter) {
        set_arguments(kernel, static_cast<cl_uint>(end), queries.leaf.get(), queries.face.get(), queries.root.get(), queries.mode.get(),
                      queries.offset_index.get(), offset_memory, node_boxes.get(), children_.get(), node_face_.get(), max_face_.get(), capacity,
                      counter.get(), out.buffer.get());
      },
      first);
}

void DevicePipeline::vertex_boxes(const Buffer& x0, const Buffer& x1, StageEvents& events) {
  const std::size_t vertices = scene_->topology().num_vertices();
  vertex_boxes_.reserve(*context_, std::max<std::size_t>(vertices, 1) * 6 * sizeof(double));
  cl_kernel kernel = context_->kernel("vertex_boxes");
  set_arguments(kernel, static_cast<cl_uint>(vertices), x0.get(), x1.get(), scene_->thickness() / 2, vertex_boxes_.get());
  launch(*context_, kernel, vertices, group_, events.add("boxes"));
}

std::size_t DevicePipeline::expand(const Buffer& candidates, std::size_t count, DeviceList& out, StageEvents& events, std::size_t first) {
  // A budgeted list is filled by ranges of candidates, each with 32-bit counts; a whole step's must keep its own.
  if (out.limit == 0 && count > kMaxCandidatesPerStep) {
    throw std::runtime_error(label_ + ": " + std::to_string(count) + " candidate triangle pairs in one step; at most " +
                             std::to_string(kMaxCandidatesPerStep) + " keep the elementary count within 32-bit indices");
  }
  if (out.capacity == 0) out.capacity = initial_elementary_capacity_;
  return fill_list(
      "expand", count, out, sizeof(cl_uint4), events, "expansion",
      [&](cl_kernel kernel, cl_uint capacity, const Buffer& counter) {
        set_arguments(kernel, static_cast<cl_uint>(first + count), candidates.get(), masks_.get(), faces_.get(), face_edges_.get(), edges_.get(),
                      vertex_boxes_.get(), capacity, counter.get(), out.buffer.get());
      },
      first);
}

std::size_t DevicePipeline::filter(const Buffer& elementary, std::size_t count, const Buffer& x0, const Buffer& x1, DeviceList& out,
                                   StageEvents& events) {
  Context& context = *context_;
  reserve_pairs(keep_, count, 1);
  cl_kernel kernel = context.kernel("separation");
  set_arguments(kernel, static_cast<cl_uint>(count), elementary.get(), faces_.get(), x0.get(), x1.get(), scene_->thickness(), keep_.get());
  launch(context, kernel, count, narrow_group(kernel), events.add("distance heuristic"));
  if (out.capacity == 0) out.capacity = initial_elementary_capacity_;
  return fill_list("compact_kept", count, out, sizeof(cl_uint4), events, "distance heuristic",
                   [&](cl_kernel compact, cl_uint capacity, const Buffer& counter) {
                     set_arguments(compact, static_cast<cl_uint>(count), elementary.get(), keep_.get(), capacity, counter.get(), out.buffer.get());
                   });
}

std::size_t DevicePipeline::narrow_group(cl_kernel kernel) const {
  // 64, or less where the kernel's resources allow less. Always the same for a kernel: PoCL compiles a kernel anew
  // for each work-group size it meets.
  std::size_t largest = 0;
  check(clGetKernelWorkGroupInfo(kernel, device_.id, CL_KERNEL_WORK_GROUP_SIZE, sizeof(largest), &largest, nullptr), "clGetKernelWorkGroupInfo");
  std::size_t group = 64;
  while (group > largest && group > 1) group /= 2;
  return group;
}

void DevicePipeline::launch_conservative(const Buffer& pairs, std::size_t count, long limit, const Buffer& status, const Buffer& toi,
                                         const Buffer& x0, const Buffer& x1, StageEvents& events) {
  cl_kernel kernel = context_->kernel("narrow_conservative");
  const cl_double tolerance = narrow_phase_.form.accuracy, toi_tolerance = narrow_phase_.form.toi_tolerance;
  const cl_long max_iterations = narrow_phase_.form.max_iterations, give_up_after = limit;
  set_arguments(kernel, static_cast<cl_uint>(count), pairs.get(), faces_.get(), x0.get(), x1.get(), scene_->thickness(), tolerance, toi_tolerance,
                max_iterations, give_up_after, status.get(), toi.get());
  launch(*context_, kernel, count, narrow_group(kernel), events.add("narrow phase"));
}

void DevicePipeline::device_pass(StageEvents& events, const std::vector<std::size_t>& which, long limit, const std::vector<cl_uint4>& pairs,
                                 std::vector<cl_uchar>& status, std::vector<double>& toi, const Buffer& x0, const Buffer& x1, bool deep) {
  Context& context = *context_;
  std::vector<cl_uint4> retry(which.size());
  for (std::size_t j = 0; j < which.size(); ++j) retry[j] = pairs[which[j]];
  reserve_pairs(retry_pairs_, retry.size(), sizeof(cl_uint4));
  upload(context, retry_pairs_, retry.data(), retry.size(), events.add("narrow phase"));
  reserve_pairs(retry_status_, retry.size(), 1);
  reserve_pairs(retry_toi_, retry.size(), sizeof(double));
  if (deep) {
    launch_deep(retry_pairs_, retry.size(), x0, x1, events);
  } else {
    launch_conservative(retry_pairs_, retry.size(), limit, retry_status_, retry_toi_, x0, x1, events);
  }
  std::vector<cl_uchar> retry_status(retry.size());
  std::vector<double> retry_toi(retry.size());
  download(context, retry_status_, retry_status.data(), retry.size(), events.add("download"));
  download(context, retry_toi_, retry_toi.data(), retry.size(), events.add("download"));
  for (std::size_t j = 0; j < which.size(); ++j) {
    status[which[j]] = retry_status[j];
    toi[which[j]] = retry_toi[j];
  }
}

void DevicePipeline::back_end(const Buffer& elementary, std::size_t count, const StepView& step, const Buffer& x0, const Buffer& x1,
                              strategies::StepResult& result, StageEvents& events) {
  Decided decided;
  decide(elementary, count, step, x0, x1, result, events, decided);
  collect(decided, result);
}

void DevicePipeline::decide(const Buffer& elementary, std::size_t count, const StepView& step, const Buffer& x0, const Buffer& x1,
                            strategies::StepResult& result, StageEvents& events, Decided& into) {
  Context& context = *context_;
  reserve_pairs(status_, count, 1);
  reserve_pairs(toi_, count, sizeof(double));
  const bool conservative = narrow_phase_.conservative();
  if (conservative) {
    launch_conservative(elementary, count, backend_.device_iterations, status_, toi_, x0, x1, events);
  } else {
    cl_kernel kernel = context.kernel("narrow_cubic");
    const cl_double eta = narrow_phase_.form.accuracy;
    set_arguments(kernel, static_cast<cl_uint>(count), elementary.get(), faces_.get(), x0.get(), x1.get(), scene_->thickness(), eta, status_.get(),
                  toi_.get());
    launch(context, kernel, count, narrow_group(kernel), events.add("narrow phase"));
  }
  // The compaction of what collides (or needs another pass).
  const std::size_t kept =
      fill_list("compact", count, out_, sizeof(cl_uint4), events, "narrow phase", [&](cl_kernel kernel, cl_uint capacity, const Buffer& counter) {
        reserve_pairs(out_status_, out_.capacity, 1);
        reserve_pairs(out_toi_, out_.capacity, sizeof(double));
        set_arguments(kernel, static_cast<cl_uint>(count), elementary.get(), status_.get(), toi_.get(), capacity, counter.get(), out_.buffer.get(),
                      out_status_.get(), out_toi_.get());
      });
  std::vector<cl_uint4> pairs(kept);
  std::vector<cl_uchar> status(kept);
  std::vector<double> toi(kept);
  download(context, out_.buffer, pairs.data(), kept, events.add("download"));
  download(context, out_status_, status.data(), kept, events.add("download"));
  download(context, out_toi_, toi.data(), kept, events.add("download"));
  // Queries the device handed back, decided by the same code: those given up after device_iterations (status 2)
  // in tiers on the device, a second pass that gives up after kSecondPassIterations (most finish there, side by
  // side), then the rest in a pass without a limit; those out of a work item's sub-boxes (status 3, which no pass
  // with the same sub-boxes mends) in the deep pass, with kDeepSubBoxFactor times as many in device memory; on the
  // host whatever that too hands back. (Until issue 51 the host also took up to 2 given-up queries a thread instead
  // of a device pass. Until issue 66 the host took every status 3: 6,400 queries a step of the paper's pile at
  // δ = 0, a third of its time on 64 cores and two thirds on 16, reports/gpus.)
  std::vector<std::size_t> given_up;
  for (std::size_t i = 0; i < kept; ++i) {
    if (status[i] >= 2) given_up.push_back(i);
  }
  // The queries still handed back: all of them, or only those given up (status 2).
  const auto handed_back = [&](bool only_given_up) {
    std::vector<std::size_t> left;
    for (const std::size_t i : given_up) {
      if (only_given_up ? status[i] == 2 : status[i] >= 2) left.push_back(i);
    }
    return left;
  };
  std::size_t second_pass = 0, third_pass = 0;
  if (conservative) {
    // Each later pass's wall time (it ends with a blocking download): part of the "narrow phase" stage, counted
    // apart so that the latency of a few long queries shows (reports/narrowphase/stages.md).
    std::vector<std::size_t> left;
    const auto timed_pass = [&](long limit, double& milliseconds) {
      const auto start = std::chrono::steady_clock::now();
      device_pass(events, left, limit, pairs, status, toi, x0, x1);
      milliseconds += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    };
    for (const long limit : {kSecondPassIterations, 0L}) {
      left = handed_back(true);
      if (left.empty()) break;
      (limit > 0 ? second_pass : third_pass) = left.size();
      timed_pass(limit, limit > 0 ? into.second_pass_ms : into.third_pass_ms);
    }
    // What is left overflowed a work item's sub-boxes (status 3): the deep pass, with more of them in device memory.
    deep_pass(events, handed_back(false), pairs, status, toi, x0, x1, into);
  }
  const std::vector<std::size_t> on_host = handed_back(false);
  {
    ScopedStageTimer timer(result.stages, "host narrow phase");
    const narrowphase::NarrowPhase& host = *narrow_phase_.host;
    tbb::parallel_for(std::size_t{0}, on_host.size(), [&](std::size_t j) {
      const std::size_t i = on_host[j];
      const cl_uint4& p = pairs[i];
      const narrowphase::NarrowPhaseResult r =
          p.s[2] == kVertexFacePair
              ? host.vertex_face(pair_rows(scene_->topology(), step.x0, step.x1, VertexFacePair{p.s[0], p.s[1]}), scene_->thickness())
              : host.edge_edge(pair_rows(scene_->topology(), step.x0, step.x1, edge_pair(p)), scene_->thickness());
      status[i] = r.collides ? 1 : 0;
      toi[i] = r.toi;
    });
  }
  {
    // What collides, kept for the collision set (collect): the strategy's own work, in its "output" stage.
    ScopedStageTimer timer(result.stages, "output");
    for (std::size_t i = 0; i < kept; ++i) {
      if (status[i] != 1) continue;
      into.pairs.push_back(pairs[i]);
      into.toi.push_back(toi[i]);
    }
  }
  into.given_up += given_up.size();
  into.second_pass += second_pass;
  into.third_pass += third_pass;
  into.on_host += on_host.size();
}

void DevicePipeline::collect(const Decided& decided, strategies::StepResult& result) const {
  {
    // The collision set from what the device kept, in chunks put in order in parallel and merged: the strategy's
    // own work, timed as its "output" stage (it was in no stage).
    ScopedStageTimer timer(result.stages, "output");
    const std::size_t kept = decided.pairs.size();
    const std::size_t host_threads = static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
    // Chunks of at least kOutputChunk pairs: sorted side by side and merged in a tree (normalize_in_parallel).
    const std::size_t chunks = std::max<std::size_t>(1, std::min(host_threads, kept / kOutputChunk));
    std::vector<CollisionSet> parts(chunks);
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t c) {
      for (std::size_t i = c * kept / chunks; i < (c + 1) * kept / chunks; ++i) {
        const cl_uint4& p = decided.pairs[i];
        if (p.s[2] == kVertexFacePair) {
          parts[c].add(VertexFacePair{p.s[0], p.s[1]}, decided.toi[i]);
        } else {
          parts[c].add(edge_pair(p), decided.toi[i]);
        }
      }
    });
    std::vector<CollisionSet*> sets;
    for (CollisionSet& part : parts) sets.push_back(&part);
    result.collisions = strategies::normalize_in_parallel(std::move(sets));
  }
  result.counters.extra.emplace_back("device_given_up_pairs", static_cast<double>(decided.given_up));
  result.counters.extra.emplace_back("device_second_pass_pairs", static_cast<double>(decided.second_pass));
  result.counters.extra.emplace_back("device_third_pass_pairs", static_cast<double>(decided.third_pass));
  result.counters.extra.emplace_back("device_second_pass_ms", decided.second_pass_ms);
  result.counters.extra.emplace_back("device_third_pass_ms", decided.third_pass_ms);
  result.counters.extra.emplace_back("device_deep_pass_pairs", static_cast<double>(decided.deep_pass));
  result.counters.extra.emplace_back("device_deep_pass_colliding", static_cast<double>(decided.deep_colliding));
  result.counters.extra.emplace_back("device_deep_pass_ms", decided.deep_pass_ms);
  result.counters.extra.emplace_back("host_decided_pairs", static_cast<double>(decided.on_host));
}

strategies::TestedPairs DevicePipeline::tested_pairs(const Buffer& elementary, std::size_t count) {
  strategies::TestedPairs tested;
  add_tested_pairs(elementary, count, tested);
  sort_tested(tested);
  return tested;
}

void DevicePipeline::add_tested_pairs(const Buffer& elementary, std::size_t count, strategies::TestedPairs& tested) {
  std::vector<cl_uint4> all(count);
  download(*context_, elementary, all.data(), count);
  for (const cl_uint4& p : all) {
    if (p.s[2] == kVertexFacePair) {
      tested.vertex_face.push_back({p.s[0], p.s[1]});
    } else {
      tested.edge_edge.push_back(edge_pair(p));
    }
  }
}

void DevicePipeline::sort_tested(strategies::TestedPairs& tested) {
  tbb::parallel_sort(tested.vertex_face.begin(), tested.vertex_face.end());
  tbb::parallel_sort(tested.edge_edge.begin(), tested.edge_edge.end());
}

std::size_t DevicePipeline::bytes() const {
  std::size_t total = 0;
  for (const Buffer* b : {&keep_,          &faces_,       &face_edges_,       &edges_,        &masks_,         &children_,
                          &node_face_,     &max_face_,    &leaf_node_buffer_, &all_.leaves,   &moving_.leaves, &all_.levels,
                          &moving_.levels, &all_.offsets, &moving_.offsets,   &vertex_boxes_, &counter_,       &status_,
                          &toi_,           &out_.buffer,  &out_status_,       &out_toi_,      &retry_pairs_,   &retry_status_,
                          &retry_toi_,     &deep_store_}) {
    total += b->bytes();
  }
  return total;
}

void add_launch_and_wait(strategies::StepResult& result, std::chrono::steady_clock::time_point started) {
  const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
  const double named = result.stages.total_milliseconds();
  // Device stages are the device's own times; where they overlap the host's, the sum can pass the wall: nothing
  // is left to name then.
  if (wall > named) result.stages.add("launch and wait", wall - named);
}

}  // namespace ccd::opencl
