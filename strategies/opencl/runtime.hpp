#pragma once
/// @file
/// A small runtime over the OpenCL C API (ocl-icd and the distribution's headers): device listing and choice, one
/// context and in-order profiling queue per user at a time (kept for the next: lease_context), programs built from the kernels embedded at build time (and
/// their binaries cached per device, so a second strategy on one device does not compile again), buffers that
/// grow and are reused, and per-stage device times from events.
///
/// Every OpenCL failure becomes an OpenClError naming the call and the error code; a program that fails to build
/// carries the build log.

#define CL_TARGET_OPENCL_VERSION 120
#include "strategies/backend.hpp"

#include <CL/cl.h>

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ccd::opencl {

struct OpenClError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What `ccdbench devices` lists and what device choice reads. A plain value, so tests can make one up.
struct DeviceInfo {
  /// Position in the listing (platforms in order, their devices in order): what device=INDEX names.
  std::size_t index = 0;
  std::string platform;
  std::string name;
  std::string vendor;
  std::string version;
  std::string driver;
  bool is_gpu = false;
  unsigned compute_units = 0;
  std::uint64_t global_memory = 0;
  std::uint64_t max_allocation = 0;
  std::size_t max_work_group_size = 0;
  /// cl_khr_fp64 (or OpenCL 1.2+ double support): every narrow phase here is double.
  bool fp64 = false;
  /// CL_FP_DENORM in CL_DEVICE_DOUBLE_FP_CONFIG: subnormal doubles are kept, not flushed.
  bool fp64_denormals = false;
  /// cl_khr_int64_base_atomics: apccd's pending list is a hash table of 64-bit pair keys.
  bool int64_atomics = false;
  cl_device_id id = nullptr;
};

/// Every device of every platform (empty when there is no platform, e.g. no ICD installed).
std::vector<DeviceInfo> list_devices();

/// The device `selector` names: "" for the node's GPUs taken in turn (`turn.turn` modulo their count: the first GPU
/// for a process alone), else its devices so; a number for that index; otherwise the first device whose name
/// contains the text (case-sensitive). When a node runs more processes than it has devices to take in turn, the
/// first choice a process makes says on stderr which device it shares.
/// @throws std::invalid_argument listing the devices when none matches, or when there are none.
DeviceInfo choose_device(const std::vector<DeviceInfo>& devices, const std::string& selector,
                         strategies::DeviceTurn turn = strategies::device_turn());

/// Whether `selector` names several devices at once: "all", or indices joined by '+' ("0+1"; any other text with a
/// '+' is a name to look for).
bool names_several_devices(const std::string& selector);

/// The devices a selector names: "all" for every GPU of this machine (every device where it has no GPU), "0+1" for
/// those indices (each once), anything else the one device choose_device gives. MPI ranks' turns do not apply to
/// "all": a process that takes every GPU shares them with the other ranks of its node.
/// @throws std::invalid_argument as choose_device, or for an index named twice.
std::vector<DeviceInfo> choose_devices(const std::vector<DeviceInfo>& devices, const std::string& selector);

/// Refuses a device that cannot run the backend: no fp64, or fp64 that flushes subnormals (the narrow phases'
/// error bounds count subnormals). The seam where a device's capabilities are judged, so a test can hand it a
/// device without fp64.
/// @throws std::invalid_argument saying what the device lacks.
void require_double_precision(const DeviceInfo& device);

/// Bytes of one sub-box on the device (ccd_sub_box in narrowphase/shared/sub_boxes.h: six doubles and a counter;
/// self_test.cpp checks it against the host's).
inline constexpr std::size_t kSubBoxBytes = 56;
/// The third component of a vertex-face pair's uint4 (CCD_VERTEX_FACE in kernels/full.cl); an edge-edge pair's
/// four are its vertices.
inline constexpr cl_uint kVertexFacePair = 0xFFFFFFFFu;

class Context;
/// Gives a leased context back to the process's pool (lease_context).
struct ContextReturn {
  void operator()(Context* context) const;
};
using ContextLease = std::unique_ptr<Context, ContextReturn>;

/// A context on `device` with the program built with `defines`: one a finished strategy gave back, else a new one.
/// Each strategy holds its own while it lives (no two share a queue or a kernel's arguments); given back, a context
/// waits for the next strategy on that device. Making one (context, queue, program from the cached binary, the
/// arithmetic self-test) and releasing it took 0.14 s a cell on an H200 (reports/gpus), as long as many a paper
/// scene's steps; a sweep made one per cell. A context whose queue reports an error when given back is
/// released, not kept.
ContextLease lease_context(const DeviceInfo& device, const std::string& defines);

/// How many contexts this process has made (not leased again): what a test of the pool counts.
std::size_t contexts_made();

/// Releases every idle context (those leased now are kept when given back): the next lease makes a new one.
void release_idle_contexts();

/// One context and one in-order queue with profiling on a device, and the program built for it.
class Context {
 public:
  /// Builds the embedded kernels for `device` with `defines` (e.g. "-DCCD_GROUP_SIZE=256"); never with flags
  /// that change the arithmetic (shared/geometry.h).
  Context(const DeviceInfo& device, const std::string& defines);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  const DeviceInfo& device() const { return device_; }
  const std::string& defines() const { return defines_; }
  cl_context context() const { return context_; }
  cl_command_queue queue() const { return queue_; }
  /// The programs a context builds from the embedded kernels: `main` when it is made; `deep` (-DCCD_DEEP_PASS: the
  /// conservative search with its sub-boxes in device memory, kernels/prelude.cl) the first time one of its kernels
  /// is asked for.
  enum class Build { main, deep };
  /// The kernel named `name` in `build`'s program (created once).
  cl_kernel kernel(const std::string& name, Build build = Build::main);
  /// Waits for every enqueued command.
  void finish();
  /// Whether the device's arithmetic passed check_device_arithmetic in this context (a kept context is not checked
  /// again: its device and program are the same).
  bool arithmetic_checked = false;
  /// The same for the deep pass's build (check_deep_pass_arithmetic), made when a conservative strategy prepares.
  bool deep_pass_checked = false;

 private:
  friend ContextLease lease_context(const DeviceInfo& device, const std::string& defines);
  DeviceInfo device_;
  std::string defines_;
  cl_context context_ = nullptr;
  cl_command_queue queue_ = nullptr;
  /// Builds the embedded kernels with `defines` (the cached binary when this process built them before).
  cl_program build_program(const std::string& defines) const;
  struct BuiltKernel {
    Build build;
    cl_kernel kernel;
  };
  std::array<cl_program, 2> programs_{};
  std::vector<std::pair<std::string, BuiltKernel>> kernels_;
};

/// A device buffer that grows (never shrinks) and is reused across steps.
class Buffer {
 public:
  Buffer() = default;
  ~Buffer();
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  /// Ensures room for `bytes` (contents are lost when it grows: by half again, to spare later steps a reallocation,
  /// but never past `limit` bytes unless `bytes` itself is: a budgeted list stays within its room).
  void reserve(Context& context, std::size_t bytes, std::size_t limit = static_cast<std::size_t>(-1));
  /// The same, but a grown buffer keeps its first `keep` bytes (copied on the device, queue-ordered).
  void reserve_keeping(Context& context, std::size_t bytes, std::size_t keep);
  cl_mem get() const { return memory_; }
  std::size_t bytes() const { return bytes_; }
  /// Gives the memory back when the buffer holds more than `bytes` (a budget that shrank its room); the next
  /// reserve allocates again.
  void release_above(std::size_t bytes);

 private:
  cl_mem memory_ = nullptr;
  std::size_t bytes_ = 0;
};

/// Events grouped by stage name; their device times are read once the queue has finished.
class StageEvents {
 public:
  ~StageEvents();
  /// A slot for the event of a command of `stage` (pass it as the command's event).
  cl_event* add(const char* stage);
  /// Milliseconds per stage (in first-use order), from CL_PROFILING_COMMAND_START to _END; releases the events.
  std::vector<std::pair<std::string, double>> collect();
  /// Of the commands collected last: milliseconds from the first one's start to the last one's end, and the part of
  /// that span in no profiled command: the device waiting on the host between commands (launches, blocking reads),
  /// and the few commands enqueued without an event (a list's counter reset and read, a grown buffer's copy). A
  /// profile of where a step's "launch and wait" goes (issue 36).
  double span_milliseconds() const { return span_; }
  double idle_milliseconds() const { return idle_; }

 private:
  std::vector<std::pair<const char*, cl_event>> events_;
  double span_ = 0, idle_ = 0;
};

/// Throws OpenClError "CALL failed: NAME (CODE)" unless `status` is CL_SUCCESS.
void check(cl_int status, const char* call);

/// Sets kernel arguments in order (buffers as cl_mem, scalars by value).
template <class... Arguments>
void set_arguments(cl_kernel kernel, const Arguments&... arguments) {
  cl_uint index = 0;
  (check(clSetKernelArg(kernel, index++, sizeof(Arguments), &arguments), "clSetKernelArg"), ...);
}

/// Writes `count` values to `buffer` (grown to hold them; at least one entry) without waiting.
template <class T>
void upload(Context& context, Buffer& buffer, const T* data, std::size_t count, cl_event* event = nullptr) {
  buffer.reserve(context, (count > 0 ? count : 1) * sizeof(T));
  if (count == 0) return;
  check(clEnqueueWriteBuffer(context.queue(), buffer.get(), CL_FALSE, 0, count * sizeof(T), data, 0, nullptr, event), "clEnqueueWriteBuffer");
}

/// Reads the first `count` values of `buffer`, waiting for them.
template <class T>
void download(Context& context, const Buffer& buffer, T* data, std::size_t count, cl_event* event = nullptr) {
  if (count == 0) return;
  check(clEnqueueReadBuffer(context.queue(), buffer.get(), CL_TRUE, 0, count * sizeof(T), data, 0, nullptr, event), "clEnqueueReadBuffer");
}

/// Enqueues `kernel` over `items` work items (rounded up to whole groups of `group`; group 0 lets the implementation
/// choose); nothing for 0 items.
void launch(Context& context, cl_kernel kernel, std::size_t items, std::size_t group, cl_event* event);
/// The same over work items [first, first + items) (a global offset: get_global_id(0) starts at `first`), for a
/// kernel that is given first + items as its count.
void launch_range(Context& context, cl_kernel kernel, std::size_t first, std::size_t items, std::size_t group, cl_event* event);

}  // namespace ccd::opencl
