#include "strategies/opencl/runtime.hpp"

#include "strategies/opencl/kernel_source.hpp"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>

namespace ccd::opencl {
namespace {

const char* error_name(cl_int code) {
  switch (code) {
    case CL_DEVICE_NOT_FOUND: return "CL_DEVICE_NOT_FOUND";
    case CL_DEVICE_NOT_AVAILABLE: return "CL_DEVICE_NOT_AVAILABLE";
    case CL_COMPILER_NOT_AVAILABLE: return "CL_COMPILER_NOT_AVAILABLE";
    case CL_MEM_OBJECT_ALLOCATION_FAILURE: return "CL_MEM_OBJECT_ALLOCATION_FAILURE";
    case CL_OUT_OF_RESOURCES: return "CL_OUT_OF_RESOURCES";
    case CL_OUT_OF_HOST_MEMORY: return "CL_OUT_OF_HOST_MEMORY";
    case CL_PROFILING_INFO_NOT_AVAILABLE: return "CL_PROFILING_INFO_NOT_AVAILABLE";
    case CL_BUILD_PROGRAM_FAILURE: return "CL_BUILD_PROGRAM_FAILURE";
    case CL_INVALID_VALUE: return "CL_INVALID_VALUE";
    case CL_INVALID_DEVICE: return "CL_INVALID_DEVICE";
    case CL_INVALID_BINARY: return "CL_INVALID_BINARY";
    case CL_INVALID_BUILD_OPTIONS: return "CL_INVALID_BUILD_OPTIONS";
    case CL_INVALID_KERNEL_NAME: return "CL_INVALID_KERNEL_NAME";
    case CL_INVALID_ARG_INDEX: return "CL_INVALID_ARG_INDEX";
    case CL_INVALID_ARG_VALUE: return "CL_INVALID_ARG_VALUE";
    case CL_INVALID_ARG_SIZE: return "CL_INVALID_ARG_SIZE";
    case CL_INVALID_KERNEL_ARGS: return "CL_INVALID_KERNEL_ARGS";
    case CL_INVALID_WORK_GROUP_SIZE: return "CL_INVALID_WORK_GROUP_SIZE";
    case CL_INVALID_BUFFER_SIZE: return "CL_INVALID_BUFFER_SIZE";
    case CL_INVALID_MEM_OBJECT: return "CL_INVALID_MEM_OBJECT";
    case -1001: return "CL_PLATFORM_NOT_FOUND_KHR";
    default: return "OpenCL error";
  }
}

std::string device_string(cl_device_id device, cl_device_info what) {
  std::size_t size = 0;
  if (clGetDeviceInfo(device, what, 0, nullptr, &size) != CL_SUCCESS || size == 0) return "";
  std::string text(size, '\0');
  check(clGetDeviceInfo(device, what, size, text.data(), nullptr), "clGetDeviceInfo");
  text.resize(std::strlen(text.c_str()));
  return text;
}

template <class T>
T device_value(cl_device_id device, cl_device_info what) {
  T value{};
  check(clGetDeviceInfo(device, what, sizeof(T), &value, nullptr), "clGetDeviceInfo");
  return value;
}

/// Program binaries already built, per device and build options: a second context on the same device loads the
/// binary instead of compiling again (PoCL compiles through LLVM, seconds per program).
struct BinaryCache {
  std::mutex mutex;
  std::map<std::pair<cl_device_id, std::string>, std::vector<unsigned char>> binaries;
};
BinaryCache& binary_cache() {
  static BinaryCache cache;
  return cache;
}

std::string build_log(cl_program program, cl_device_id device) {
  std::size_t size = 0;
  clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, 0, nullptr, &size);
  std::string log(size, '\0');
  if (size > 0) clGetProgramBuildInfo(program, device, CL_PROGRAM_BUILD_LOG, size, log.data(), nullptr);
  log.resize(std::strlen(log.c_str()));
  return log;
}

}  // namespace

void check(cl_int status, const char* call) {
  if (status != CL_SUCCESS) {
    throw OpenClError(std::string("OpenCL: ") + call + " failed: " + error_name(status) + " (" + std::to_string(status) + ")");
  }
}

std::vector<DeviceInfo> list_devices() {
  cl_uint platform_count = 0;
  // No ICD, or an ICD loader without platforms, answers an error here: that is "no devices", not a failure.
  if (clGetPlatformIDs(0, nullptr, &platform_count) != CL_SUCCESS || platform_count == 0) return {};
  std::vector<cl_platform_id> platforms(platform_count);
  check(clGetPlatformIDs(platform_count, platforms.data(), nullptr), "clGetPlatformIDs");
  std::vector<DeviceInfo> devices;
  for (cl_platform_id platform : platforms) {
    std::size_t size = 0;
    std::string platform_name;
    if (clGetPlatformInfo(platform, CL_PLATFORM_NAME, 0, nullptr, &size) == CL_SUCCESS && size > 0) {
      platform_name.assign(size, '\0');
      clGetPlatformInfo(platform, CL_PLATFORM_NAME, size, platform_name.data(), nullptr);
      platform_name.resize(std::strlen(platform_name.c_str()));
    }
    cl_uint device_count = 0;
    if (clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, 0, nullptr, &device_count) != CL_SUCCESS || device_count == 0) continue;
    std::vector<cl_device_id> ids(device_count);
    check(clGetDeviceIDs(platform, CL_DEVICE_TYPE_ALL, device_count, ids.data(), nullptr), "clGetDeviceIDs");
    for (cl_device_id id : ids) {
      DeviceInfo info;
      info.index = devices.size();
      info.platform = platform_name;
      info.name = device_string(id, CL_DEVICE_NAME);
      info.vendor = device_string(id, CL_DEVICE_VENDOR);
      info.version = device_string(id, CL_DEVICE_VERSION);
      info.driver = device_string(id, CL_DRIVER_VERSION);
      info.is_gpu = (device_value<cl_device_type>(id, CL_DEVICE_TYPE) & CL_DEVICE_TYPE_GPU) != 0;
      info.compute_units = device_value<cl_uint>(id, CL_DEVICE_MAX_COMPUTE_UNITS);
      info.global_memory = device_value<cl_ulong>(id, CL_DEVICE_GLOBAL_MEM_SIZE);
      info.max_allocation = device_value<cl_ulong>(id, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
      info.max_work_group_size = device_value<std::size_t>(id, CL_DEVICE_MAX_WORK_GROUP_SIZE);
      const cl_device_fp_config fp64 = device_value<cl_device_fp_config>(id, CL_DEVICE_DOUBLE_FP_CONFIG);
      const std::string extensions = device_string(id, CL_DEVICE_EXTENSIONS);
      info.fp64 = fp64 != 0 && extensions.find("cl_khr_fp64") != std::string::npos;
      info.fp64_denormals = (fp64 & CL_FP_DENORM) != 0;
      info.int64_atomics = extensions.find("cl_khr_int64_base_atomics") != std::string::npos;
      info.id = id;
      devices.push_back(std::move(info));
    }
  }
  return devices;
}

namespace {

std::string listing(const std::vector<DeviceInfo>& devices) {
  std::string text;
  for (const DeviceInfo& d : devices) text += (text.empty() ? "" : ", ") + std::to_string(d.index) + ": " + d.name;
  return text.empty() ? "none (is an OpenCL ICD such as pocl-opencl-icd installed?)" : text;
}

}  // namespace

DeviceInfo choose_device(const std::vector<DeviceInfo>& devices, const std::string& selector, strategies::DeviceTurn turn) {
  if (devices.empty()) throw std::invalid_argument("no OpenCL device: " + listing(devices));
  if (selector.empty()) {
    std::vector<const DeviceInfo*> turns;
    for (const DeviceInfo& d : devices) {
      if (d.is_gpu) turns.push_back(&d);
    }
    if (turns.empty()) {
      for (const DeviceInfo& d : devices) turns.push_back(&d);
    }
    const std::size_t slot = static_cast<std::size_t>(std::max(turn.turn, 0)) % turns.size();
    const DeviceInfo& chosen = *turns[slot];
    // Another turn takes this device when one of this slot's next turns, slot + size, is below the count.
    if (static_cast<long long>(slot + turns.size()) < turn.of) {
      static std::once_flag said;
      std::call_once(said, [&] {
        std::cerr << "ccdbench: " << turn.of << " processes on this node take " << turns.size() << (turns[0]->is_gpu ? " GPU" : " OpenCL device")
                  << (turns.size() == 1 ? "" : "s") << " in turn: this one (turn " << turn.turn << ") shares device " << chosen.index << " ("
                  << chosen.name << "); name one per process with device=INDEX, or start fewer ranks a node\n";
      });
    }
    return chosen;
  }
  if (std::all_of(selector.begin(), selector.end(), [](char c) { return c >= '0' && c <= '9'; }) && selector.size() < 6) {
    const std::size_t index = std::stoul(selector);
    if (index < devices.size()) return devices[index];
    throw std::invalid_argument("device=" + selector + ": no device with that index (devices: " + listing(devices) + ")");
  }
  for (const DeviceInfo& d : devices) {
    if (d.name.find(selector) != std::string::npos) return d;
  }
  throw std::invalid_argument("device=" + selector + ": no device name contains it (devices: " + listing(devices) + ")");
}

bool names_several_devices(const std::string& selector) {
  // Indices joined by '+' only: a device name may hold a '+' (AMD's "gfx90a:sramecc+:xnack-"), and selects by its text.
  if (selector == "all") return true;
  if (selector.find('+') == std::string::npos || selector.front() == '+' || selector.back() == '+') return false;
  return std::all_of(selector.begin(), selector.end(), [](char c) { return c == '+' || (c >= '0' && c <= '9'); });
}

std::vector<DeviceInfo> choose_devices(const std::vector<DeviceInfo>& devices, const std::string& selector) {
  if (!names_several_devices(selector)) return {choose_device(devices, selector)};
  if (devices.empty()) throw std::invalid_argument("no OpenCL device: " + listing(devices));
  std::vector<DeviceInfo> chosen;
  if (selector == "all") {
    for (const DeviceInfo& d : devices) {
      if (d.is_gpu) chosen.push_back(d);
    }
    if (chosen.empty()) chosen = devices;
    return chosen;
  }
  std::stringstream parts(selector);
  for (std::string part; std::getline(parts, part, '+');) {
    const bool index = !part.empty() && part.size() < 6 && std::all_of(part.begin(), part.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!index) throw std::invalid_argument("device=" + selector + ": '" + part + "' is not a device index (devices: " + listing(devices) + ")");
    const DeviceInfo d = choose_device(devices, part);
    for (const DeviceInfo& taken : chosen) {
      if (taken.index == d.index) throw std::invalid_argument("device=" + selector + ": device " + part + " is named twice");
    }
    chosen.push_back(d);
  }
  return chosen;
}

void require_double_precision(const DeviceInfo& device) {
  if (!device.fp64) {
    throw std::invalid_argument("OpenCL device " + std::to_string(device.index) + " (" + device.name +
                                ") has no double precision (cl_khr_fp64), which every narrow phase of the OpenCL "
                                "backend needs; choose another with device=INDEX (see `ccdbench devices`)");
  }
  if (!device.fp64_denormals) {
    throw std::invalid_argument("OpenCL device " + std::to_string(device.index) + " (" + device.name +
                                ") flushes subnormal doubles to zero (no CL_FP_DENORM), which the conservative "
                                "narrow phase's error bounds do not allow; choose another with device=INDEX");
  }
}

Context::Context(const DeviceInfo& device, const std::string& defines) : device_(device), defines_(defines) {
  require_double_precision(device);
  cl_int status = CL_SUCCESS;
  context_ = clCreateContext(nullptr, 1, &device_.id, nullptr, nullptr, &status);
  check(status, "clCreateContext");
  queue_ = clCreateCommandQueue(context_, device_.id, CL_QUEUE_PROFILING_ENABLE, &status);
  check(status, "clCreateCommandQueue");
  programs_[static_cast<std::size_t>(Build::main)] = build_program(defines_);
}

cl_program Context::build_program(const std::string& defines) const {
  // Build options: the defines only, never an option that relaxes the arithmetic (mad enabling, fast or unsafe
  // math, finite math only, denormals as zero): the kernels must compute what the host computes.
  // CCDBENCH_OPENCL_BUILD_LOG=1: the build log on stderr after each build, with NVIDIA's -cl-nv-verbose (each
  // kernel's registers and spills: what a change to the shared text does to occupancy; a diagnostic, it changes no
  // arithmetic).
  const bool log_build = std::getenv("CCDBENCH_OPENCL_BUILD_LOG") != nullptr;
  const bool nvidia = device_.vendor.find("NVIDIA") != std::string::npos;
  const std::string options = "-cl-std=CL1.2 " + defines + (log_build && nvidia ? " -cl-nv-verbose" : "");
  BinaryCache& cache = binary_cache();
  std::lock_guard lock(cache.mutex);
  const auto key = std::make_pair(device_.id, options);
  const auto cached = cache.binaries.find(key);
  cl_int status = CL_SUCCESS;
  cl_program program = nullptr;
  if (cached != cache.binaries.end()) {
    const unsigned char* binary = cached->second.data();
    const std::size_t size = cached->second.size();
    cl_int binary_status = CL_SUCCESS;
    program = clCreateProgramWithBinary(context_, 1, &device_.id, &size, &binary, &binary_status, &status);
    if (status != CL_SUCCESS || binary_status != CL_SUCCESS) {
      if (program != nullptr) clReleaseProgram(program);
      program = nullptr;
    }
  }
  if (program == nullptr) {
    const char* source = kernel_source();
    program = clCreateProgramWithSource(context_, 1, &source, nullptr, &status);
    check(status, "clCreateProgramWithSource");
  }
  status = clBuildProgram(program, 1, &device_.id, options.c_str(), nullptr, nullptr);
  if (status != CL_SUCCESS) {
    const std::string log = build_log(program, device_.id);
    clReleaseProgram(program);
    throw OpenClError("OpenCL: the kernels do not build on device " + std::to_string(device_.index) + " (" + device_.name +
                      "): " + error_name(status) + "\n" + log);
  }
  if (log_build) std::cerr << "OpenCL build log (" << device_.name << ", " << options << "):\n" << build_log(program, device_.id) << "\n";
  if (cached == cache.binaries.end()) {
    std::size_t size = 0;
    if (clGetProgramInfo(program, CL_PROGRAM_BINARY_SIZES, sizeof(size), &size, nullptr) == CL_SUCCESS && size > 0) {
      std::vector<unsigned char> binary(size);
      unsigned char* pointer = binary.data();
      if (clGetProgramInfo(program, CL_PROGRAM_BINARIES, sizeof(pointer), &pointer, nullptr) == CL_SUCCESS) {
        cache.binaries.emplace(key, std::move(binary));
      }
    }
  }
  return program;
}

namespace {

/// Contexts finished strategies gave back, per device and build defines (lease_context). Never destroyed: at the
/// process's exit an OpenCL implementation may already be tearing itself down (PoCL's own static destructors), and
/// releasing a context then can crash; the process's end frees what it holds.
struct ContextPool {
  using Idle = std::map<std::pair<cl_device_id, std::string>, std::vector<std::unique_ptr<Context>>>;
  std::mutex mutex;
  Idle idle;
};
ContextPool& context_pool() {
  static ContextPool* const pool = new ContextPool;
  return *pool;
}
/// Idle contexts kept per device and defines: --interleave holds one per strategy of a scene at once (a run's
/// strategies are a handful); more than that are released.
constexpr std::size_t kIdleContextsKept = 4;

/// Contexts made by lease_context (contexts_made).
std::atomic<std::size_t> g_contexts_made{0};

}  // namespace

std::size_t contexts_made() { return g_contexts_made.load(); }

void release_idle_contexts() {
  ContextPool::Idle idle;
  {
    ContextPool& pool = context_pool();
    std::lock_guard lock(pool.mutex);
    idle.swap(pool.idle);
  }  // (released here, outside the pool's lock)
}

ContextLease lease_context(const DeviceInfo& device, const std::string& defines) {
  require_double_precision(device);
  {
    ContextPool& pool = context_pool();
    std::lock_guard lock(pool.mutex);
    const auto idle = pool.idle.find({device.id, defines});
    if (idle != pool.idle.end() && !idle->second.empty()) {
      ContextLease lease(idle->second.back().release());
      idle->second.pop_back();
      lease->device_ = device;  // the caller's description of the same device
      return lease;
    }
  }
  ContextLease made(new Context(device, defines));
  ++g_contexts_made;
  return made;
}

void ContextReturn::operator()(Context* context) const {
  std::unique_ptr<Context> owned(context);
  // A queue in error (a kernel that failed, a device lost) is not handed to the next strategy: released here.
  if (owned == nullptr || clFinish(owned->queue()) != CL_SUCCESS) return;
  ContextPool& pool = context_pool();
  std::lock_guard lock(pool.mutex);
  std::vector<std::unique_ptr<Context>>& idle = pool.idle[{owned->device().id, owned->defines()}];
  if (idle.size() < kIdleContextsKept) idle.push_back(std::move(owned));
}

Context::~Context() {
  // Writes enqueued without waiting read host memory until they run: a strategy destroyed after an error must not
  // free that memory under them.
  if (queue_ != nullptr) clFinish(queue_);
  for (auto& [name, kernel] : kernels_) clReleaseKernel(kernel.kernel);
  for (cl_program program : programs_) {
    if (program != nullptr) clReleaseProgram(program);
  }
  if (queue_ != nullptr) clReleaseCommandQueue(queue_);
  if (context_ != nullptr) clReleaseContext(context_);
}

cl_kernel Context::kernel(const std::string& name, Build build) {
  for (auto& [known, kernel] : kernels_) {
    if (known == name && kernel.build == build) return kernel.kernel;
  }
  cl_program& program = programs_[static_cast<std::size_t>(build)];
  // The deep pass's build when first asked for (DevicePipeline::prepare asks, for a conservative narrow phase).
  if (program == nullptr) program = build_program(build == Build::deep ? defines_ + " -DCCD_DEEP_PASS" : defines_);
  cl_int status = CL_SUCCESS;
  cl_kernel kernel = clCreateKernel(program, name.c_str(), &status);
  check(status, ("clCreateKernel(" + name + ")").c_str());
  kernels_.push_back({name, {build, kernel}});
  return kernel;
}

void Context::finish() { check(clFinish(queue_), "clFinish"); }

Buffer::~Buffer() {
  if (memory_ != nullptr) clReleaseMemObject(memory_);
}

void Buffer::release_above(std::size_t bytes) {
  if (bytes_ <= bytes || memory_ == nullptr) return;
  clReleaseMemObject(memory_);
  memory_ = nullptr;
  bytes_ = 0;
}

void Buffer::reserve_keeping(Context& context, std::size_t bytes, std::size_t keep) {
  if (bytes <= bytes_ && memory_ != nullptr) return;
  Buffer old;
  std::swap(old.memory_, memory_);
  std::swap(old.bytes_, bytes_);
  reserve(context, std::max(bytes, old.bytes_ + old.bytes_ / 2));
  keep = std::min(keep, old.bytes_);
  if (keep > 0) {
    check(clEnqueueCopyBuffer(context.queue(), old.memory_, memory_, 0, 0, keep, 0, nullptr, nullptr), "clEnqueueCopyBuffer");
    context.finish();  // the old buffer is released below
  }
}

void Buffer::reserve(Context& context, std::size_t bytes, std::size_t limit) {
  if (bytes <= bytes_ && memory_ != nullptr) return;
  const std::size_t grown = std::max(bytes, std::min(limit, std::max<std::size_t>(bytes_ + bytes_ / 2, 64)));
  if (grown > context.device().max_allocation) {
    throw OpenClError("OpenCL: a buffer of " + std::to_string(grown) + " bytes is more than device " + std::to_string(context.device().index) + " (" +
                      context.device().name + ") allocates at once (" + std::to_string(context.device().max_allocation) + ")");
  }
  if (memory_ != nullptr) clReleaseMemObject(memory_);
  memory_ = nullptr;
  bytes_ = 0;
  cl_int status = CL_SUCCESS;
  memory_ = clCreateBuffer(context.context(), CL_MEM_READ_WRITE, grown, nullptr, &status);
  check(status, "clCreateBuffer");
  bytes_ = grown;
}

StageEvents::~StageEvents() {
  for (auto& [stage, event] : events_) {
    if (event != nullptr) clReleaseEvent(event);
  }
}

cl_event* StageEvents::add(const char* stage) {
  events_.emplace_back(stage, nullptr);
  return &events_.back().second;
}

std::vector<std::pair<std::string, double>> StageEvents::collect() {
  std::vector<std::pair<std::string, double>> stages;
  cl_ulong first = ~cl_ulong{0}, last = 0;
  double busy = 0;
  for (auto& [stage, event] : events_) {
    if (event == nullptr) continue;
    cl_ulong start = 0, end = 0;
    check(clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_START, sizeof(start), &start, nullptr), "clGetEventProfilingInfo");
    check(clGetEventProfilingInfo(event, CL_PROFILING_COMMAND_END, sizeof(end), &end, nullptr), "clGetEventProfilingInfo");
    clReleaseEvent(event);
    event = nullptr;
    first = std::min(first, start);
    last = std::max(last, end);
    const double milliseconds = static_cast<double>(end - start) * 1e-6;
    busy += milliseconds;
    const auto known = std::find_if(stages.begin(), stages.end(), [&](const auto& entry) { return entry.first == stage; });
    if (known != stages.end()) {
      known->second += milliseconds;
    } else {
      stages.emplace_back(stage, milliseconds);
    }
  }
  events_.clear();
  // An in-order queue runs one command at a time: the span less their sum is the time between them (or in commands
  // enqueued without an event).
  span_ = last > first ? static_cast<double>(last - first) * 1e-6 : 0;
  idle_ = std::max(0.0, span_ - busy);
  return stages;
}

void launch(Context& context, cl_kernel kernel, std::size_t items, std::size_t group, cl_event* event) {
  launch_range(context, kernel, 0, items, group, event);
}

void launch_range(Context& context, cl_kernel kernel, std::size_t first, std::size_t items, std::size_t group, cl_event* event) {
  if (items == 0) return;
  // Without a group size the implementation chooses one (it must divide the global size: a multiple of 64).
  const std::size_t step = group == 0 ? 64 : group;
  const std::size_t global = (items + step - 1) / step * step;
  check(clEnqueueNDRangeKernel(context.queue(), kernel, 1, first == 0 ? nullptr : &first, &global, group == 0 ? nullptr : &group, 0, nullptr, event),
        "clEnqueueNDRangeKernel");
}

}  // namespace ccd::opencl
