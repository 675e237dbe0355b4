/// @file
/// The OpenCL backend's entry points in a build without OpenCL (CCDBENCH_WITH_OPENCL=OFF), built instead of
/// full_opencl.cpp and apccd/opencl/apccd_opencl.cpp: each refuses, saying how to get the backend.

#include "strategies/apccd/opencl/apccd_opencl.hpp"
#include "strategies/opencl/full_opencl.hpp"

#include <stdexcept>
#include <string>

namespace ccd::strategies {
namespace {

constexpr const char* kHowToGetOpenCl =
    "this build has CCDBENCH_WITH_OPENCL=OFF (install ocl-icd-opencl-dev opencl-headers pocl-opencl-icd, which scripts/setup.sh does, and "
    "reconfigure)";

[[noreturn]] void refuse_backend() { throw std::invalid_argument(std::string("backend=opencl is not available: ") + kHowToGetOpenCl); }

}  // namespace

std::vector<OpenClDeviceSummary> opencl_devices() { throw std::invalid_argument(std::string("OpenCL is not available: ") + kHowToGetOpenCl); }

std::string opencl_device_name(const std::string&, const BackendChoice&, const narrowphase::ResolvedNarrowPhase&, bool) { refuse_backend(); }

std::unique_ptr<Strategy> make_full_opencl(std::unique_ptr<narrowphase::NarrowPhase>, const BackendChoice&, bool) { refuse_backend(); }

std::unique_ptr<Strategy> make_apccd_opencl(const ApccdSettings&, std::unique_ptr<narrowphase::NarrowPhase>, const BackendChoice&) {
  refuse_backend();
}

}  // namespace ccd::strategies
