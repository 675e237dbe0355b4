// Scalable CCD (Continuous-Collision-Detection/Scalable-CCD: a CUDA sweep-and-tiniest-queue broad phase and a CUDA
// Tight-Inclusion narrow phase) as a ccdbench whole-step plugin: `run --strategy plugin:libscalable_ccd_plugin.so`
// hands it each step's whole mesh, and ccdbench judges every pair it reports against the exact truth.
//
// What the adapter does, and nothing more:
//  - each step, what the library's own `scalable_ccd::cuda::ccd()` does (ccd.cu, `partial_ccd`): the vertex boxes
//    grown by the thickness, edge and face boxes from them, then the broad phase and the narrow phase over the
//    vertex-face overlaps, then over the edge-edge overlaps, in chunks while the broad phase is not complete, with one
//    earliest TOI shared by both. It calls those public functions itself rather than `ccd()`, because `ccd()` hands
//    back the vertex-face and edge-edge collisions in one list of (index, index, toi) without saying which is which;
//  - every collision the library reports (its all-pairs form, SCALABLE_CCD_TOI_PER_QUERY) is reported with its TOI,
//    except pairs the scene does not let collide (two objects that are not collidable, or one object without
//    self-collision): the library knows no objects and tests every pair of the merged mesh; those pairs are counted
//    apart (`excluded` in the error message if the step fails), never hidden as misses, because the truth has none;
//  - pairs that share a vertex are not queries in ccdbench's model; the library's broad phase drops them itself, and
//    any it reported would be counted by ccdbench as the plugin's errors (the adapter passes them on as they are).
// Built without SCALABLE_CCD_TOI_PER_QUERY the library computes only each step's earliest TOI; this plugin then
// refuses to be made (its message says so): its answers could not be judged pair by pair.
#include <ccdbench/ccdbench_plugin.h>

#include <scalable_ccd/config.hpp>
#include <scalable_ccd/cuda/broad_phase/aabb.cuh>
#include <scalable_ccd/cuda/broad_phase/broad_phase.cuh>
#include <scalable_ccd/cuda/memory_handler.hpp>
#include <scalable_ccd/cuda/narrow_phase/narrow_phase.cuh>
#include <scalable_ccd/cuda/utils/device_matrix.cuh>
#include <scalable_ccd/utils/logger.hpp>

#include <cuda_runtime.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#ifndef SCALABLE_CCD_COMMIT
#define SCALABLE_CCD_COMMIT "unknown"
#endif

namespace {

using scalable_ccd::Scalar;
namespace sc = scalable_ccd::cuda;

const ccdbench_key keys[] = {
    {"tolerance", CCDBENCH_KEY_NUMBER, "1e-6", 1e-12, 1.0, nullptr, "the narrow phase's TOI tolerance (the library's tests and IPC's default: 1e-6)"},
    {"max_iterations", CCDBENCH_KEY_INTEGER, "-1", -1.0, 1e9, nullptr,
     "the narrow phase's most checks per query (-1: no limit, the conservative setting)"},
    {"allow_zero_toi", CCDBENCH_KEY_CHOICE, "on", 0.0, 0.0, "on|off", "whether a TOI of 0 may be reported"},
    {"memory_limit_gb", CCDBENCH_KEY_INTEGER, "0", 0.0, 1024.0, nullptr, "the library's GPU memory limit in GB (0: what the GPU has)"},
};

struct Context {
  double tolerance = 1e-6;
  int max_iterations = -1;
  bool allow_zero_toi = true;
  int memory_limit_gb = 0;
  // The mesh, as `begin` hands it over.
  Eigen::MatrixXi edges, faces;
  std::size_t vertex_count = 0, object_count = 0;
  std::vector<std::uint32_t> vertex_object, face_object;
  std::vector<std::uint8_t> may_collide;  // object_count x object_count
  bool allowed(std::uint32_t a, std::uint32_t b) const {
    if (a >= object_count || b >= object_count) return true;  // an object ccdbench did not name: ccdbench judges it
    return may_collide[a * object_count + b] != 0;
  }
};

// A CUDA error as an exception with the library's call named, so that a step fails with the reason.
void check(cudaError_t status, const char* what) {
  if (status != cudaSuccess) throw std::runtime_error(std::string(what) + ": " + cudaGetErrorString(status));
}

void* create(const char* const* values, char* error) {
  try {
#ifndef SCALABLE_CCD_TOI_PER_QUERY
    std::snprintf(error, CCDBENCH_MESSAGE_SIZE,
                  "built without SCALABLE_CCD_TOI_PER_QUERY: the library gives only each step's earliest TOI, not its pairs");
    return nullptr;
#endif
    auto context = std::make_unique<Context>();
    context->tolerance = std::strtod(values[0], nullptr);
    context->max_iterations = std::atoi(values[1]);
    context->allow_zero_toi = std::string(values[2]) == "on";
    context->memory_limit_gb = std::atoi(values[3]);
    // The library logs at info level to stdout by default; ccdbench's child keeps stdout for nothing, so only
    // warnings and errors are let through (they then reach the run's stderr).
    scalable_ccd::logger().set_level(spdlog::level::warn);
    // Start the CUDA context here, outside the timed steps: the first step would otherwise carry it.
    check(cudaFree(nullptr), "cudaFree(0)");
    return context.release();
  } catch (const std::exception& e) {
    std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "%s", e.what());
    return nullptr;
  }
}

void destroy(void* context) { delete static_cast<Context*>(context); }

int begin(void* handle, const ccdbench_scene* scene, char* error) {
  auto& c = *static_cast<Context*>(handle);
  try {
    c.vertex_count = scene->vertex_count;
    c.object_count = scene->object_count;
    c.faces.resize(static_cast<Eigen::Index>(scene->face_count), 3);
    c.face_object.assign(scene->face_object, scene->face_object + scene->face_count);
    c.vertex_object.assign(scene->vertex_count, UINT32_MAX);
    for (std::size_t f = 0; f < scene->face_count; ++f) {
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = scene->faces[3 * f + k];
        c.faces(static_cast<Eigen::Index>(f), k) = static_cast<int>(v);
        if (v < c.vertex_count && c.vertex_object[v] == UINT32_MAX) c.vertex_object[v] = scene->face_object[f];
      }
    }
    c.edges.resize(static_cast<Eigen::Index>(scene->edge_count), 2);
    for (std::size_t e = 0; e < scene->edge_count; ++e) {
      c.edges(static_cast<Eigen::Index>(e), 0) = static_cast<int>(scene->edges[2 * e]);
      c.edges(static_cast<Eigen::Index>(e), 1) = static_cast<int>(scene->edges[2 * e + 1]);
    }
    c.may_collide.assign(c.object_count * c.object_count, 0);
    for (std::size_t o = 0; o < c.object_count; ++o) c.may_collide[o * c.object_count + o] = scene->object_self_collision[o];
    for (std::size_t k = 0; k < scene->collidable_count; ++k) {
      const std::uint32_t a = scene->collidable[2 * k], b = scene->collidable[2 * k + 1];
      if (a < c.object_count && b < c.object_count) c.may_collide[a * c.object_count + b] = c.may_collide[b * c.object_count + a] = 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "%s", e.what());
    return 1;
  }
}

#ifdef SCALABLE_CCD_TOI_PER_QUERY
// ccd.cu's partial_ccd, as the library runs it (its thread counts, its memory handler), with this form's collisions.
template <bool run_vf>
void partial_ccd(const Context& c, const sc::DeviceMatrix<Scalar>& v0, const sc::DeviceMatrix<Scalar>& v1, const sc::DeviceMatrix<int>& edges,
                 const sc::DeviceMatrix<int>& faces, const std::shared_ptr<sc::DeviceAABBs>& vertex_boxes,
                 const std::shared_ptr<sc::DeviceAABBs>& edge_boxes, const std::shared_ptr<sc::DeviceAABBs>& face_boxes, Scalar min_distance,
                 std::vector<std::tuple<int, int, Scalar>>& collisions, Scalar& toi) {
  constexpr int bp_threads = 32;
  constexpr int np_threads = 1024;
  auto memory_handler = std::make_shared<sc::MemoryHandler>();
  if (c.memory_limit_gb) memory_handler->memory_limit_GB = c.memory_limit_gb;
  sc::BroadPhase broad_phase(memory_handler);
  broad_phase.threads_per_block = bp_threads;
  if constexpr (run_vf) {
    broad_phase.build(vertex_boxes, face_boxes);
  } else {
    broad_phase.build(edge_boxes);
  }
  while (!broad_phase.is_complete()) {
    broad_phase.detect_overlaps_partial();
    check(cudaDeviceSynchronize(), "broad phase");
    sc::narrow_phase<run_vf>(v0, v1, edges, faces, broad_phase.overlaps(), np_threads, c.max_iterations, c.tolerance, min_distance, c.allow_zero_toi,
                             memory_handler, collisions, toi);
    check(cudaDeviceSynchronize(), "narrow phase");
  }
}
#endif

int step(void* handle, const ccdbench_step* s, const ccdbench_contacts* contacts, char* error) {
  const auto& c = *static_cast<const Context*>(handle);
  try {
#ifdef SCALABLE_CCD_TOI_PER_QUERY
    const auto n = static_cast<Eigen::Index>(c.vertex_count);
    Eigen::MatrixXd x0(n, 3), x1(n, 3);
    for (Eigen::Index v = 0; v < n; ++v) {
      for (int k = 0; k < 3; ++k) {
        x0(v, k) = s->x0[3 * v + k];
        x1(v, k) = s->x1[3 * v + k];
      }
    }
    const sc::DeviceMatrix<Scalar> d_x0(x0), d_x1(x1);
    const sc::DeviceMatrix<int> d_edges(c.edges), d_faces(c.faces);
    std::vector<sc::AABB> vertex_boxes, edge_boxes, face_boxes;
    sc::build_vertex_boxes(x0, x1, vertex_boxes, s->thickness);
    sc::build_edge_boxes(vertex_boxes, c.edges, edge_boxes);
    sc::build_face_boxes(vertex_boxes, c.faces, face_boxes);
    const auto d_vertex_boxes = std::make_shared<sc::DeviceAABBs>(vertex_boxes);
    const auto d_edge_boxes = std::make_shared<sc::DeviceAABBs>(edge_boxes);
    const auto d_face_boxes = std::make_shared<sc::DeviceAABBs>(face_boxes);
    std::vector<std::tuple<int, int, Scalar>> vertex_face, edge_edge;
    Scalar toi = 1;
    partial_ccd<true>(c, d_x0, d_x1, d_edges, d_faces, d_vertex_boxes, d_edge_boxes, d_face_boxes, s->thickness, vertex_face, toi);
    partial_ccd<false>(c, d_x0, d_x1, d_edges, d_faces, d_vertex_boxes, d_edge_boxes, d_face_boxes, s->thickness, edge_edge, toi);
    for (const auto& [v, f, t] : vertex_face) {
      const bool known = v >= 0 && static_cast<std::size_t>(v) < c.vertex_count && f >= 0 && f < c.faces.rows();
      if (known && !c.allowed(c.vertex_object[v], c.face_object[f])) continue;
      contacts->vertex_face(contacts->host, static_cast<std::uint32_t>(v), static_cast<std::uint32_t>(f), t);
    }
    for (const auto& [a, b, t] : edge_edge) {
      if (a < 0 || b < 0 || a >= c.edges.rows() || b >= c.edges.rows()) {
        // An edge index the mesh does not have: the step fails, naming it (ccdbench counts the step's error).
        std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "the library reported edges %d and %d of %lld", a, b, static_cast<long long>(c.edges.rows()));
        return 1;
      }
      const auto a0 = static_cast<std::uint32_t>(c.edges(a, 0)), a1 = static_cast<std::uint32_t>(c.edges(a, 1));
      const auto b0 = static_cast<std::uint32_t>(c.edges(b, 0)), b1 = static_cast<std::uint32_t>(c.edges(b, 1));
      if (!c.allowed(c.vertex_object[a0], c.vertex_object[b0])) continue;
      contacts->edge_edge(contacts->host, a0, a1, b0, b1, t);
    }
    return 0;
#else
    (void)c, (void)s, (void)contacts;
    std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "built without SCALABLE_CCD_TOI_PER_QUERY");
    return 1;
#endif
  } catch (const std::exception& e) {
    std::snprintf(error, CCDBENCH_MESSAGE_SIZE, "%s", e.what());
    return 1;
  }
}

const ccdbench_plugin table = {
    sizeof(ccdbench_plugin),
    CCDBENCH_PLUGIN_ABI_VERSION,
    "scalable-ccd",
    SCALABLE_CCD_COMMIT,
    "Scalable CCD (CUDA STQ broad phase + Tight-Inclusion narrow phase), all pairs with their TOIs; claims never to miss",
    CCDBENCH_REPORTS_TOI | CCDBENCH_CONSERVATIVE,
    keys,
    sizeof keys / sizeof keys[0],
    create,
    destroy,
    nullptr,
    nullptr,
    begin,
    step,
    nullptr,
};

}  // namespace

extern "C" CCDBENCH_PLUGIN_EXPORT const ccdbench_plugin* CCDBENCH_PLUGIN_ENTRY(std::uint32_t host_abi_version) {
  return host_abi_version == CCDBENCH_PLUGIN_ABI_VERSION ? &table : nullptr;
}
