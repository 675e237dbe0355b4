#include "strategies/backend.hpp"

#include <stdexcept>

namespace ccd::strategies {

namespace {

// device_iterations: 0 (never give up) or up to the largest iteration cap a narrow phase takes. list_start: 0 (sized
// from the scene) up to the 2^32 - 1 entries a kernel indexes. sub_boxes: 4 (the least one query's search starts
// with) up to 1024 (56 kB of private memory a work item, far past what any device keeps in registers).
constexpr narrowphase::SpecRange kDeviceIterationRange{0.0, narrowphase::kIterationRange.maximum};
constexpr narrowphase::SpecRange kListStartRange{0.0, 4294967295.0};
constexpr narrowphase::SpecRange kSubBoxRange{4.0, 1024.0};

}  // namespace

std::vector<narrowphase::KeySpec> backend_keys() {
  using narrowphase::KeySpec;
  const BackendChoice defaults;
  return {KeySpec::choice("backend", {"cpu", "opencl"}, defaults.backend, "where every stage runs: TBB threads, or an OpenCL device"),
          KeySpec::text("device", "backend=opencl: device INDEX or NAME-SUBSTRING (`ccdbench devices`); default the first GPU, else 0"),
          KeySpec::integer("device_iterations", defaults.device_iterations, kDeviceIterationRange,
                           "backend=opencl: iterations a work item spends on a conservative query before handing it on (0: never)"),
          KeySpec::integer("list_start", static_cast<long>(defaults.list_start), kListStartRange,
                           "backend=opencl: entries each device list starts with (0: sized from the scene); lists grow"),
          KeySpec::integer("sub_boxes", defaults.sub_boxes, kSubBoxRange,
                           "backend=opencl: sub-boxes a work item holds for a conservative query; more are handed on")};
}

BackendChoice read_backend(const narrowphase::SpecReader& keys) {
  BackendChoice choice;
  choice.backend = keys.choice("backend");
  for (const char* key : {"device", "device_iterations", "list_start", "sub_boxes"}) {
    if (keys.given(key) && !choice.opencl()) {
      throw std::invalid_argument(std::string(key) + " is a key of the OpenCL backend: it needs backend=opencl");
    }
  }
  choice.device = keys.text("device");
  choice.device_iterations = keys.integer("device_iterations");
  choice.list_start = static_cast<std::size_t>(keys.integer("list_start"));
  choice.sub_boxes = keys.integer("sub_boxes");
  return choice;
}

std::string BackendChoice::resolved(const std::string& device_name, bool conservative) const {
  if (!opencl()) return "";
  std::string text = ":backend=opencl:device=" + device_name;
  if (conservative) text += ":device_iterations=" + std::to_string(device_iterations);
  if (list_start != 0) text += ":list_start=" + std::to_string(list_start);
  if (sub_boxes != kDefaultDeviceSubBoxes) text += ":sub_boxes=" + std::to_string(sub_boxes);
  return text;
}

}  // namespace ccd::strategies
