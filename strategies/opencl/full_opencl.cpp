#include "strategies/opencl/full_opencl.hpp"

#include "ccd/config.hpp"
#include "core/assignment.hpp"
#include "strategies/bvh/bvh.hpp"
#include "strategies/narrowphase/cubic.hpp"
#include "strategies/narrowphase/inclusion.hpp"
#include "strategies/narrowphase/narrow_phase.hpp"

#if CCDBENCH_WITH_OPENCL
#include "strategies/opencl/runtime.hpp"
#include "strategies/opencl/self_test.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/parallel_sort.h>
#endif

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

namespace ccd::strategies {

std::vector<std::string> backend_parameter_names() { return {"backend", "device", "device_iterations"}; }

// device_iterations: 0 (never give up) or up to the largest iteration cap a narrow phase takes (1e9).
constexpr narrowphase::SpecRange kDeviceIterationRange{0.0, 1e9, true};

BackendChoice take_backend(std::map<std::string, std::string>& parameters) {
  BackendChoice choice;
  if (const auto it = parameters.find("backend"); it != parameters.end()) {
    choice.backend = it->second;
    parameters.erase(it);
  }
  if (choice.backend != "cpu" && choice.backend != "opencl") {
    throw std::invalid_argument("backend=" + choice.backend + " is not a backend (cpu, opencl)");
  }
  for (const char* key : {"device", "device_iterations"}) {
    const auto it = parameters.find(key);
    if (it == parameters.end()) continue;
    if (choice.backend != "opencl") throw std::invalid_argument(std::string(key) + "=" + it->second + " is a key of the OpenCL backend: it needs backend=opencl");
    if (std::string(key) == "device") {
      choice.device = it->second;
    } else {
      choice.device_iterations = static_cast<long>(narrowphase::parse_spec_number("full", key, it->second, kDeviceIterationRange));
    }
    parameters.erase(it);
  }
  return choice;
}

#if CCDBENCH_WITH_OPENCL
namespace {

using opencl::Buffer;
using opencl::check;
using opencl::launch;
using opencl::set_arguments;

/// Work-group size of the kernels that reserve list space per group (CCD_GROUP_SIZE): 256, or the device's
/// largest power of two below that.
std::size_t group_size_for(const opencl::DeviceInfo& device) {
  std::size_t group = 256;
  while (group > device.max_work_group_size && group > 1) group /= 2;
  return group;
}

using opencl::download;
using opencl::upload;

class FullOpenCl final : public Strategy {
 public:
  /// `parameters`: the narrow phase's spec keys, read here as the CPU's factory reads them (every digit).
  FullOpenCl(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase, std::string narrow_phase_name,
             const narrowphase::NarrowPhaseParameters& parameters, opencl::DeviceInfo device, long device_iterations)
      : narrow_phase_(std::move(narrow_phase)), narrow_phase_name_(std::move(narrow_phase_name)), device_(std::move(device)),
        device_iterations_(device_iterations) {
    if (narrow_phase_name_ == "conservative") {
      inclusion_ = narrowphase::read_inclusion_settings(parameters);
    } else {
      cubic_ = narrowphase::read_cubic_settings(narrow_phase_name_, parameters);
    }
  }

  std::string name() const override {
    return "full+" + narrow_phase_->name() + ":backend=opencl:device=" + device_.name +
           (narrow_phase_name_ == "conservative" ? ":device_iterations=" + std::to_string(device_iterations_) : "");
  }

  void init(const Scene& scene, std::span<const Vec3> first_frame) override {
    scene_ = &scene;
    group_ = group_size_for(device_);
    // Test hook (tests/opencl): lists start with room for one entry and a work item holds 4 sub-boxes, so that the
    // growing of lists and the host's share of the conservative queries run on small scenes too.
    const char* tiny_hook = std::getenv("CCDBENCH_OPENCL_TEST_TINY");
    tiny_ = tiny_hook != nullptr && std::string(tiny_hook) == "1";
    context_ = std::make_unique<opencl::Context>(device_, "-DCCD_GROUP_SIZE=" + std::to_string(group_) +
                                                              (tiny_ ? " -DCCD_DEVICE_SUB_BOXES=4" : ""));
    opencl::check_device_arithmetic(*context_);
    const MeshTopology& topology = scene.topology();
    num_vertices_ = topology.num_vertices();
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
    context_->finish();

    // Static objects are fitted once, here, over frame 0 (as the CPU does): every leaf and every level now.
    upload(*context_, x_[0], first_frame.data()->data(), 3 * num_vertices_);
    upload(*context_, x_[1], first_frame.data()->data(), 3 * num_vertices_);
    refit(all_, x_[0], x_[1], nullptr);
    context_->finish();
    last_step_ = static_cast<std::size_t>(-1);
  }

  StepResult step(const StepView& step, bool audit) override {
    StepResult result;
    opencl::StageEvents events;
    opencl::Context& context = *context_;
    // Steps come in order: x0 of this step is x1 of the last, already on the device. Otherwise both are sent.
    const bool follows = step.index == last_step_ + 1;
    if (!follows) upload(context, x_[current_], step.x0.data()->data(), 3 * num_vertices_, events.add("upload"));
    Buffer& x0 = x_[current_];
    Buffer& x1 = x_[1 - current_];
    upload(context, x1, step.x1.data()->data(), 3 * num_vertices_, events.add("upload"));

    const double half = scene_->thickness() / 2;
    {
      vertex_boxes_.reserve(context, std::max<std::size_t>(num_vertices_, 1) * 6 * sizeof(double));
      cl_kernel kernel = context.kernel("vertex_boxes");
      set_arguments(kernel, static_cast<cl_uint>(num_vertices_), x0.get(), x1.get(), half, vertex_boxes_.get());
      launch(context, kernel, num_vertices_, group_, events.add("boxes"));
    }
    refit(moving_, x0, x1, &events);

    // Traversal: candidate triangle pairs.
    const std::size_t candidates = fill_list(context, "traverse", query_count_, candidates_, sizeof(cl_uint2), candidate_capacity_,
                                             events, "traversal", [&](cl_kernel kernel, cl_uint capacity) {
                                               set_arguments(kernel, static_cast<cl_uint>(query_count_), q_leaf_.get(), q_face_.get(),
                                                             q_root_.get(), q_self_.get(), node_boxes_.get(), children_.get(),
                                                             node_face_.get(), capacity, counter_.get(), candidates_.get());
                                             });
    if (candidates > kMaxCandidatesPerStep) {
      throw std::runtime_error("full:backend=opencl: " + std::to_string(candidates) + " candidate triangle pairs in step " +
                               std::to_string(step.index) + "; at most " + std::to_string(kMaxCandidatesPerStep) +
                               " keep the elementary count within 32-bit indices");
    }
    // Expansion: elementary pairs that pass the primitive-level box test.
    const std::size_t elementary = fill_list(context, "expand", candidates, elementary_, sizeof(cl_uint4), elementary_capacity_, events,
                                             "expansion", [&](cl_kernel kernel, cl_uint capacity) {
                                               set_arguments(kernel, static_cast<cl_uint>(candidates), candidates_.get(), masks_.get(),
                                                             faces_.get(), face_edges_.get(), edges_.get(), vertex_boxes_.get(),
                                                             capacity, counter_.get(), elementary_.get());
                                             });
    // Narrow phase, then the compaction of what collides (or needs the host).
    status_.reserve(context, std::max<std::size_t>(elementary, 1));
    toi_.reserve(context, std::max<std::size_t>(elementary, 1) * sizeof(double));
    if (narrow_phase_name_ == "conservative") {
      launch_conservative(elementary_, elementary, device_iterations_, status_, toi_, x0, x1, events);
    } else {
      cl_kernel kernel = context.kernel("narrow_cubic");
      const cl_double eta = cubic_.eta;
      set_arguments(kernel, static_cast<cl_uint>(elementary), elementary_.get(), faces_.get(), x0.get(), x1.get(), scene_->thickness(), eta,
                    status_.get(), toi_.get());
      launch(context, kernel, elementary, narrow_group(kernel), events.add("narrow phase"));
    }
    const std::size_t kept = fill_list(context, "compact", elementary, out_pairs_, sizeof(cl_uint4), out_capacity_, events, "narrow phase",
                                       [&](cl_kernel kernel, cl_uint capacity) {
                                         out_status_.reserve(context, std::max<std::size_t>(out_capacity_, 1));
                                         out_toi_.reserve(context, std::max<std::size_t>(out_capacity_, 1) * sizeof(double));
                                         set_arguments(kernel, static_cast<cl_uint>(elementary), elementary_.get(), status_.get(),
                                                       toi_.get(), capacity, counter_.get(), out_pairs_.get(), out_status_.get(),
                                                       out_toi_.get());
                                       });
    std::vector<cl_uint4> pairs(kept);
    std::vector<cl_uchar> status(kept);
    std::vector<double> toi(kept);
    download(context, out_pairs_, pairs.data(), kept, events.add("download"));
    download(context, out_status_, status.data(), kept, events.add("download"));
    download(context, out_toi_, toi.data(), kept, events.add("download"));
    // Queries the device gave up on (past device_iterations, or out of sub-boxes), decided by the same code in
    // tiers: a second device pass that gives up after kSecondPassIterations (most finish there, side by side),
    // then the rest, long queries up to the iteration cap, either in a device pass without a limit or on the host,
    // whose threads run one long query several times faster than a work item does but are few.
    std::vector<std::size_t> given_up;
    for (std::size_t i = 0; i < kept; ++i) {
      if (status[i] == 2) given_up.push_back(i);
    }
    const std::size_t host_threads = static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
    std::size_t second_pass = 0, third_pass = 0;
    if (narrow_phase_name_ == "conservative") {
      auto still_given_up = [&] {
        std::vector<std::size_t> left;
        for (const std::size_t i : given_up) {
          if (status[i] == 2) left.push_back(i);
        }
        return left;
      };
      std::vector<std::size_t> left = given_up;
      if (left.size() > kHostQueriesPerThread * host_threads) {
        second_pass = left.size();
        device_pass(context, events, left, kSecondPassIterations, pairs, status, toi, x0, x1);
        left = still_given_up();
      }
      if (left.size() > kHostQueriesPerThread * host_threads) {
        third_pass = left.size();
        device_pass(context, events, left, 0, pairs, status, toi, x0, x1);
      }
    }
    std::vector<std::size_t> on_host;
    for (const std::size_t i : given_up) {
      if (status[i] == 2) on_host.push_back(i);
    }
    {
      ScopedStageTimer timer(result.stages, "host narrow phase");
      tbb::parallel_for(std::size_t{0}, on_host.size(), [&](std::size_t j) {
        const std::size_t i = on_host[j];
        const cl_uint4& p = pairs[i];
        const narrowphase::NarrowPhaseResult r =
            p.s[2] == kVertexFace ? narrow_phase_->vertex_face(pair_rows(scene_->topology(), step.x0, step.x1, VertexFacePair{p.s[0], p.s[1]}), scene_->thickness())
                                  : narrow_phase_->edge_edge(pair_rows(scene_->topology(), step.x0, step.x1, edge_pair(p)), scene_->thickness());
        status[i] = r.collides ? 1 : 0;
        toi[i] = r.toi;
      });
    }
    for (std::size_t i = 0; i < kept; ++i) {
      if (status[i] != 1) continue;
      const cl_uint4& p = pairs[i];
      if (p.s[2] == kVertexFace) {
        result.collisions.add(VertexFacePair{p.s[0], p.s[1]}, toi[i]);
      } else {
        result.collisions.add(edge_pair(p), toi[i]);
      }
    }
    const std::size_t host_decided = on_host.size();
    result.collisions.normalize();
    for (const auto& [stage, milliseconds] : events.collect()) result.stages.add(stage, milliseconds);
    if (audit) result.tested = tested_pairs(elementary);
    current_ = 1 - current_;
    last_step_ = step.index;
    result.counters.candidate_triangle_pairs = candidates;
    result.counters.elementary_tests = elementary;
    result.counters.history_bytes = device_bytes();
    result.counters.extra.emplace_back("device_given_up_pairs", static_cast<double>(given_up.size()));
    result.counters.extra.emplace_back("device_second_pass_pairs", static_cast<double>(second_pass));
    result.counters.extra.emplace_back("device_third_pass_pairs", static_cast<double>(third_pass));
    result.counters.extra.emplace_back("host_decided_pairs", static_cast<double>(host_decided));
    return result;
  }

 private:
  static constexpr cl_uint kVertexFace = 0xFFFFFFFFu;
  /// Given-up queries per host thread up to which the host decides them rather than another device pass. A pass
  /// costs about its longest query on a work item (10 to 30 ms on the H200 at the 20,000-iteration cap, a few ms
  /// at kSecondPassIterations); a host thread runs a query at the cap in about 10 ms, shorter ones in well under
  /// one (reports/opencl: with the host taking up to 64 per thread, three paper scenes spent 65-92 ms there).
  static constexpr std::size_t kHostQueriesPerThread = 2;
  /// The second device pass gives up after this many iterations: the queries that cloth-funnel hands back finish
  /// within it, side by side; what is left runs to the cap.
  static constexpr long kSecondPassIterations = 4000;

  /// The conservative kernel over the first `count` pairs of `pairs`, giving up after `limit` iterations (0: never),
  /// writing `status` and `toi` (sized by the caller).
  void launch_conservative(const Buffer& pairs, std::size_t count, long limit, const Buffer& status, const Buffer& toi, const Buffer& x0,
                           const Buffer& x1, opencl::StageEvents& events) {
    cl_kernel kernel = context_->kernel("narrow_conservative");
    const cl_double tolerance = inclusion_.tolerance;
    const cl_long max_iterations = inclusion_.max_iterations, give_up_after = limit;
    set_arguments(kernel, static_cast<cl_uint>(count), pairs.get(), faces_.get(), x0.get(), x1.get(), scene_->thickness(), tolerance,
                  max_iterations, give_up_after, status.get(), toi.get());
    launch(*context_, kernel, count, narrow_group(kernel), events.add("narrow phase"));
  }

  /// Runs the conservative kernel again over the pairs `which` (indices into pairs) with give_up_after `limit`
  /// (0: none), and stores their status and TOI.
  void device_pass(opencl::Context& context, opencl::StageEvents& events, const std::vector<std::size_t>& which, long limit,
                   const std::vector<cl_uint4>& pairs, std::vector<cl_uchar>& status, std::vector<double>& toi, const Buffer& x0,
                   const Buffer& x1) {
    std::vector<cl_uint4> retry(which.size());
    for (std::size_t j = 0; j < which.size(); ++j) retry[j] = pairs[which[j]];
    upload(context, retry_pairs_, retry.data(), retry.size(), events.add("narrow phase"));
    retry_status_.reserve(context, retry.size());
    retry_toi_.reserve(context, retry.size() * sizeof(double));
    launch_conservative(retry_pairs_, retry.size(), limit, retry_status_, retry_toi_, x0, x1, events);
    std::vector<cl_uchar> retry_status(retry.size());
    std::vector<double> retry_toi(retry.size());
    download(context, retry_status_, retry_status.data(), retry.size(), events.add("download"));
    download(context, retry_toi_, retry_toi.data(), retry.size(), events.add("download"));
    for (std::size_t j = 0; j < which.size(); ++j) {
      status[which[j]] = retry_status[j];
      toi[which[j]] = retry_toi[j];
    }
  }
  /// Each candidate yields at most 15 elementary pairs (6 vertex-face, 9 edge-edge): this keeps their count in 32 bits.
  static constexpr std::size_t kMaxCandidatesPerStep = 0xFFFFFFFFull / 15;
  /// Depth the traversal kernel's stack holds (CCD_TRAVERSAL_STACK in kernels/full.cl).
  static constexpr std::size_t kTraversalStack = 64;

  /// Work-group size of a narrow-phase kernel: 64, or less where the kernel's resources allow less. Always the
  /// same for a kernel: PoCL compiles a kernel anew for each work-group size it meets.
  std::size_t narrow_group(cl_kernel kernel) const {
    std::size_t largest = 0;
    check(clGetKernelWorkGroupInfo(kernel, device_.id, CL_KERNEL_WORK_GROUP_SIZE, sizeof(largest), &largest, nullptr),
          "clGetKernelWorkGroupInfo");
    std::size_t group = 64;
    while (group > largest && group > 1) group /= 2;
    return group;
  }

  static EdgeEdgePair edge_pair(const cl_uint4& p) { return {Edge{p.s[0], p.s[1]}, Edge{p.s[2], p.s[3]}}; }

  /// Builds each object's tree on the host exactly as the CPU does, flattens them into one node array, and lists
  /// the leaves and the levels (deepest first) to refit, plus the traversal queries.
  void build_hierarchies(const Scene& scene, std::span<const Vec3> first_frame) {
    std::vector<double> boxes;
    std::vector<cl_int2> children;
    std::vector<cl_uint> node_face, depth;
    std::vector<cl_uint> leaf_node(scene.topology().num_faces(), 0);
    std::vector<cl_int> root(scene.objects().size(), -1);
    std::vector<bool> moving_node;
    for (ObjectId id = 0; id < scene.objects().size(); ++id) {
      const SceneObject& object = scene.object(id);
      bvh::TriangleBvh tree;
      tree.build(scene.topology(), object.first_face, object.num_faces, first_frame);
      if (tree.empty()) continue;
      const auto base = static_cast<cl_int>(children.size());
      root[id] = base;
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
        if (node.is_leaf()) leaf_node[node.face] = static_cast<cl_uint>(base) + static_cast<cl_uint>(n);
        if (local_depth[n] + 1 >= kTraversalStack) {
          throw std::invalid_argument("full:backend=opencl: object " + object.name + "'s hierarchy is deeper than the " +
                                      std::to_string(kTraversalStack) + " levels its traversal stack holds");
        }
      }
    }
    const std::size_t node_count = children.size();
    // Leaves, and internal nodes grouped by depth, deepest first (children before parents).
    cl_uint max_depth = 0;
    for (cl_uint d : depth) max_depth = std::max(max_depth, d);
    std::vector<cl_uint> leaves_all, leaves_moving;
    std::vector<std::vector<cl_uint>> by_depth(max_depth + 1);
    for (std::size_t n = 0; n < node_count; ++n) {
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
    // Queries: each face of a self-colliding object against its own tree; for each collidable pair, the faces of
    // the larger object against the smaller one's tree (the other way round, a two-triangle ground would be two
    // work items walking the whole cloth: 9 ms of traversal on drape at resolution 100, against 0.5).
    std::vector<cl_uint> q_leaf, q_face;
    std::vector<cl_int> q_root;
    std::vector<cl_uchar> q_self;
    auto add_queries = [&](ObjectId from, ObjectId into, bool self) {
      const SceneObject& object = scene.object(from);
      if (root[into] < 0 || root[from] < 0) return;
      for (FaceId f = object.first_face; f < object.first_face + object.num_faces; ++f) {
        q_leaf.push_back(leaf_node[f]);
        q_face.push_back(f);
        q_root.push_back(root[into]);
        q_self.push_back(self ? 1 : 0);
      }
    };
    for (ObjectId id = 0; id < scene.objects().size(); ++id) {
      if (scene.object(id).self_collision) add_queries(id, id, true);
    }
    for (const auto& [a, b] : scene.collidable_pairs()) {
      if (scene.object(a).num_faces >= scene.object(b).num_faces) {
        add_queries(a, b, false);
      } else {
        add_queries(b, a, false);
      }
    }
    query_count_ = q_leaf.size();
    opencl::Context& context = *context_;
    node_boxes_.reserve(context, std::max<std::size_t>(node_count, 1) * 6 * sizeof(double));
    upload(context, children_, children.data(), children.size());
    upload(context, node_face_, node_face.data(), node_face.size());
    all_.leaf_count = leaves_all.size();
    moving_.leaf_count = leaves_moving.size();
    upload(context, all_.leaves, leaves_all.data(), leaves_all.size());
    upload(context, moving_.leaves, leaves_moving.data(), leaves_moving.size());
    upload(context, all_.levels, levels_all.data(), levels_all.size());
    upload(context, moving_.levels, levels_moving.data(), levels_moving.size());
    upload(context, q_leaf_, q_leaf.data(), q_leaf.size());
    upload(context, q_face_, q_face.data(), q_face.size());
    upload(context, q_root_, q_root.data(), q_root.size());
    upload(context, q_self_, q_self.data(), q_self.size());
    counter_.reserve(context, 2 * sizeof(cl_uint));
    candidate_capacity_ = tiny_ ? 1 : std::max<std::size_t>(4 * scene.topology().num_faces(), 1024);
    elementary_capacity_ = tiny_ ? 1 : 4 * candidate_capacity_;
    out_capacity_ = tiny_ ? 1 : 1024;
    context.finish();
  }

  /// What a refit covers: every node (at init, static objects included) or the moving objects' nodes (per step).
  struct RefitPlan {
    Buffer leaves;
    std::size_t leaf_count = 0;
    /// Internal nodes, deepest level first; level i is [level_offsets[i], level_offsets[i + 1]).
    Buffer levels;
    std::vector<std::size_t> level_offsets;
  };

  /// The plan's leaf boxes over x0 -> x1, then each of its levels (deepest first).
  void refit(const RefitPlan& plan, const Buffer& x0, const Buffer& x1, opencl::StageEvents* events) {
    opencl::Context& context = *context_;
    cl_kernel boxes = context.kernel("leaf_boxes");
    set_arguments(boxes, static_cast<cl_uint>(plan.leaf_count), plan.leaves.get(), node_face_.get(), faces_.get(), x0.get(), x1.get(),
                  scene_->thickness() / 2, node_boxes_.get());
    launch(context, boxes, plan.leaf_count, group_, events != nullptr ? events->add("boxes") : nullptr);
    cl_kernel level = context.kernel("refit_level");
    const std::vector<std::size_t>& offsets = plan.level_offsets;
    for (std::size_t i = 0; i + 1 < offsets.size(); ++i) {
      const std::size_t count = offsets[i + 1] - offsets[i];
      set_arguments(level, static_cast<cl_uint>(count), static_cast<cl_uint>(offsets[i]), plan.levels.get(), children_.get(), node_boxes_.get());
      launch(context, level, count, group_, events != nullptr ? events->add("refit") : nullptr);
    }
  }

  /// Runs a list-filling kernel: resets the counter, launches with the current capacity, reads the total; when
  /// the list did not fit, grows it to the total and runs again. Returns the total.
  template <class SetArguments>
  std::size_t fill_list(opencl::Context& context, const char* kernel_name, std::size_t items, Buffer& list, std::size_t entry_bytes,
                        std::size_t& capacity, opencl::StageEvents& events, const char* stage, SetArguments set) {
    cl_kernel kernel = context.kernel(kernel_name);
    while (true) {
      list.reserve(context, std::max<std::size_t>(capacity, 1) * entry_bytes);
      const cl_uint zero[2] = {0, 0};
      check(clEnqueueWriteBuffer(context.queue(), counter_.get(), CL_FALSE, 0, sizeof(zero), zero, 0, nullptr, nullptr), "clEnqueueWriteBuffer");
      set(kernel, static_cast<cl_uint>(std::min<std::size_t>(capacity, 0xFFFFFFFFu)));
      launch(context, kernel, items, group_, events.add(stage));
      cl_uint total[2] = {0, 0};
      download(context, counter_, total, 2);
      if (total[1] != 0) {
        throw std::runtime_error(std::string("full:backend=opencl: the ") + stage + " list of one step passed 2^32 entries");
      }
      if (total[0] <= capacity) return total[0];
      capacity = total[0] + total[0] / 4;
    }
  }

  TestedPairs tested_pairs(std::size_t elementary) {
    std::vector<cl_uint4> all(elementary);
    download(*context_, elementary_, all.data(), elementary);
    TestedPairs tested;
    for (const cl_uint4& p : all) {
      if (p.s[2] == kVertexFace) {
        tested.vertex_face.push_back({p.s[0], p.s[1]});
      } else {
        tested.edge_edge.push_back(edge_pair(p));
      }
    }
    tbb::parallel_sort(tested.vertex_face.begin(), tested.vertex_face.end());
    tbb::parallel_sort(tested.edge_edge.begin(), tested.edge_edge.end());
    return tested;
  }

  std::size_t device_bytes() const {
    std::size_t total = 0;
    for (const Buffer* b : {&x_[0], &x_[1], &faces_, &face_edges_, &edges_, &masks_, &node_boxes_, &children_, &node_face_,
                            &all_.leaves, &moving_.leaves, &all_.levels, &moving_.levels, &q_leaf_, &q_face_, &q_root_,
                            &q_self_, &vertex_boxes_, &counter_, &candidates_, &elementary_, &status_, &toi_, &out_pairs_, &out_status_,
                            &out_toi_, &retry_pairs_, &retry_status_, &retry_toi_}) {
      total += b->bytes();
    }
    return total;
  }

  std::unique_ptr<narrowphase::NarrowPhase> narrow_phase_;
  std::string narrow_phase_name_;
  opencl::DeviceInfo device_;
  narrowphase::InclusionSettings inclusion_;
  narrowphase::CubicSettings cubic_;
  const Scene* scene_ = nullptr;
  std::unique_ptr<opencl::Context> context_;
  long device_iterations_ = 0;
  std::size_t group_ = 256;
  bool tiny_ = false;
  std::size_t num_vertices_ = 0;
  std::size_t query_count_ = 0;
  std::size_t current_ = 0;
  std::size_t last_step_ = static_cast<std::size_t>(-1);
  std::size_t candidate_capacity_ = 0, elementary_capacity_ = 0, out_capacity_ = 0;
  RefitPlan all_, moving_;
  Buffer x_[2], faces_, face_edges_, edges_, masks_, node_boxes_, children_, node_face_, q_leaf_, q_face_, q_root_, q_self_, vertex_boxes_, counter_, candidates_, elementary_, status_, toi_,
      out_pairs_, out_status_, out_toi_, retry_pairs_, retry_status_, retry_toi_;
};

}  // namespace

std::vector<OpenClDeviceSummary> opencl_devices() {
  std::vector<OpenClDeviceSummary> summaries;
  for (const opencl::DeviceInfo& d : opencl::list_devices()) {
    OpenClDeviceSummary s{d.index, d.platform, d.name, d.version, d.driver, d.is_gpu, d.compute_units, d.global_memory, d.fp64, d.fp64_denormals, ""};
    try {
      opencl::require_double_precision(d);
    } catch (const std::invalid_argument& refusal) {
      s.refused_because = refusal.what();
    }
    summaries.push_back(std::move(s));
  }
  return summaries;
}

std::unique_ptr<Strategy> make_full_opencl(std::unique_ptr<narrowphase::NarrowPhase> narrow_phase, const std::string& narrow_phase_name,
                                           const narrowphase::NarrowPhaseParameters& parameters, const BackendChoice& backend) {
  if (narrow_phase_name != "conservative" && narrow_phase_name != "cubic64") {
    throw std::invalid_argument("full:backend=opencl runs the narrow phases conservative and cubic64, not " + narrow_phase_name);
  }
  opencl::DeviceInfo device = opencl::choose_device(opencl::list_devices(), backend.device);
  opencl::require_double_precision(device);
  return std::make_unique<FullOpenCl>(std::move(narrow_phase), narrow_phase_name, parameters, std::move(device), backend.device_iterations);
}

#else

std::vector<OpenClDeviceSummary> opencl_devices() {
  throw std::invalid_argument("OpenCL is not available: this build has CCDBENCH_WITH_OPENCL=OFF (install ocl-icd-opencl-dev "
                              "opencl-headers pocl-opencl-icd, which scripts/setup.sh does, and reconfigure)");
}

std::unique_ptr<Strategy> make_full_opencl(std::unique_ptr<narrowphase::NarrowPhase>, const std::string&,
                                           const narrowphase::NarrowPhaseParameters&, const BackendChoice&) {
  throw std::invalid_argument("backend=opencl is not available: this build has CCDBENCH_WITH_OPENCL=OFF (install ocl-icd-opencl-dev "
                              "opencl-headers pocl-opencl-icd, which scripts/setup.sh does, and reconfigure)");
}

#endif

}  // namespace ccd::strategies
