#include "strategies/backend.hpp"

#include "core/number_text.hpp"

#include <cmath>
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

MemoryBudget parse_memory_budget(const std::string& text) {
  const auto refuse = [&](const std::string& why) {
    return std::invalid_argument("memory=" + text + ": " + why + " (a share of the device, e.g. 75%, or bytes, e.g. 2G, 512M, 1048576)");
  };
  MemoryBudget budget;
  if (text.empty()) throw refuse("empty");
  if (text.back() == '%') {
    const std::optional<double> percent = parse_double(std::string_view(text).substr(0, text.size() - 1));
    if (!percent || !(*percent > 0 && *percent <= 100)) throw refuse("a share must be above 0% and at most 100%");
    budget.percent = *percent;
    return budget;
  }
  static const std::string kSuffixes = "KMGT";
  const std::size_t suffix = kSuffixes.find(text.back());
  const std::string digits = suffix == std::string::npos ? text : text.substr(0, text.size() - 1);
  const std::optional<double> count = parse_double(digits);
  if (!count) throw refuse("not a share or a number of bytes");
  // The suffix first (0.5K is 512 bytes), then a whole number of bytes from 1 to 2^62: far past any device, and
  // exact in both double and uint64.
  const double bytes = std::ldexp(*count, suffix == std::string::npos ? 0 : 10 * static_cast<int>(suffix + 1));
  if (!(bytes >= 1 && bytes <= 0x1p62) || bytes != std::floor(bytes)) throw refuse("not a whole number of bytes from 1 to 2^62");
  budget.bytes = static_cast<std::uint64_t>(bytes);
  return budget;
}

std::uint64_t MemoryBudget::on_device(std::uint64_t device_memory) const {
  if (bytes != 0) return bytes;
  return static_cast<std::uint64_t>(std::floor(static_cast<double>(device_memory) * percent / 100));
}

std::string MemoryBudget::text() const {
  if (bytes != 0) return std::to_string(bytes);
  return narrowphase::format_spec_number(percent) + "%";
}

std::vector<narrowphase::KeySpec> backend_keys() {
  using narrowphase::KeySpec;
  const BackendChoice defaults;
  return {KeySpec::choice("backend", {"cpu", "opencl"}, defaults.backend, "where every stage runs: TBB threads, or an OpenCL device"),
          KeySpec::text("device",
                        "backend=opencl: device INDEX or NAME-SUBSTRING (`ccdbench devices`); default the first GPU, else 0; full also "
                        "takes several for one step: all (every GPU) or INDEX+INDEX"),
          KeySpec::integer("device_iterations", defaults.device_iterations, kDeviceIterationRange,
                           "backend=opencl: iterations a work item spends on a conservative query before handing it on (0: never)"),
          KeySpec::integer("list_start", static_cast<long>(defaults.list_start), kListStartRange,
                           "backend=opencl: entries each device list starts with (0: sized from the scene); lists grow"),
          KeySpec::integer("sub_boxes", defaults.sub_boxes, kSubBoxRange,
                           "backend=opencl: sub-boxes a work item holds for a conservative query; more are handed on"),
          KeySpec::text("memory",
                        "backend=opencl: device memory a step may use: a share (default 75%) or bytes (2G, 512M); full runs a step "
                        "that does not fit in chunks, apccd refuses it")};
}

BackendChoice read_backend(const narrowphase::SpecReader& keys) {
  BackendChoice choice;
  choice.backend = keys.choice("backend");
  for (const char* key : {"device", "device_iterations", "list_start", "sub_boxes", "memory"}) {
    if (keys.given(key) && !choice.opencl()) {
      throw std::invalid_argument(std::string(key) + " is a key of the OpenCL backend: it needs backend=opencl");
    }
  }
  choice.device = keys.text("device");
  choice.device_iterations = keys.integer("device_iterations");
  choice.list_start = static_cast<std::size_t>(keys.integer("list_start"));
  choice.sub_boxes = keys.integer("sub_boxes");
  if (keys.given("memory")) choice.memory = parse_memory_budget(keys.text("memory"));
  return choice;
}

std::string BackendChoice::resolved(const std::string& device_name, bool conservative) const {
  if (!opencl()) return "";
  std::string text = ":backend=opencl:device=" + device_name;
  if (conservative) text += ":device_iterations=" + std::to_string(device_iterations);
  if (list_start != 0) text += ":list_start=" + std::to_string(list_start);
  if (sub_boxes != kDefaultDeviceSubBoxes) text += ":sub_boxes=" + std::to_string(sub_boxes);
  if (!memory.is_default()) text += ":memory=" + memory.text();
  return text;
}

namespace {
DeviceTurn g_device_turn;
}  // namespace

void set_device_turn(DeviceTurn turn) { g_device_turn = turn; }

DeviceTurn device_turn() { return g_device_turn; }

}  // namespace ccd::strategies
