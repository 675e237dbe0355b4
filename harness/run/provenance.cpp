#include "harness/run/provenance.hpp"

#include "ccd/config.hpp"
#include "ccd/git_revision.hpp"
#include "harness/cell_store.hpp"
#include "harness/work_queue.hpp"

#include <gmp.h>
#include <mpfr.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <tbb/version.h>

#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <ctime>
#include <fstream>

namespace ccd::harness {

std::size_t worker_threads() {
  return std::min<std::size_t>(static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()),
                               tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

nlohmann::json build_provenance() {
  nlohmann::json provenance = {{"ccdbench", CCDBENCH_VERSION},
                               {"git_revision", CCDBENCH_GIT_REVISION},
                               {"build_type", CCDBENCH_BUILD_TYPE},
                               {"cxx_flags", CCDBENCH_CXX_FLAGS},
                               {"compiler", CCDBENCH_COMPILER},
                               {"cgal", CCDBENCH_VERSION_CGAL},
                               {"eigen", CCDBENCH_VERSION_EIGEN},
                               {"nlohmann_json", CCDBENCH_VERSION_NLOHMANN_JSON},
                               {"gmp", gmp_version},
                               {"mpfr", mpfr_get_version()},
                               {"tbb", TBB_runtime_version()},
                               {"tbb_interface", TBB_runtime_interface_version()}};
  provenance["fcl"] = CCDBENCH_WITH_FCL ? CCDBENCH_VERSION_FCL : "not built";
  provenance["libccd"] = CCDBENCH_VERSION_LIBCCD;
  provenance["mpi"] = CCDBENCH_WITH_MPI ? mpi_library_version() : "not built";
  provenance["opencl"] = CCDBENCH_WITH_OPENCL ? std::string("OpenCL ") + CCDBENCH_VERSION_OPENCL + " headers, ICD loader" : "not built";
  // A build with plugin-boundary guards left out (scripts/guards-off.sh) says so in every record.
  if (std::string(CCDBENCH_GUARDS_OFF).size() > 0) provenance["plugin_guards_off"] = CCDBENCH_GUARDS_OFF;
  return provenance;
}

nlohmann::json environment() {
  static const nlohmann::json cached = [] {
    char host[256] = {};
    ::gethostname(host, sizeof host - 1);
    std::string cpu = "unknown";
    std::ifstream cpuinfo("/proc/cpuinfo");
    for (std::string line; std::getline(cpuinfo, line);) {
      if (line.rfind("model name", 0) == 0) {
        cpu = line.substr(line.find(':') + 2);
        break;
      }
    }
    const std::string revision = CCDBENCH_GIT_REVISION;  // of the build, not of the source folder at run time
    return nlohmann::json{{"machine", std::string(host) + " (" + cpu + ", " + std::to_string(::sysconf(_SC_NPROCESSORS_ONLN)) + " cores)"},
                          {"build_type", CCDBENCH_BUILD_TYPE},
                          {"git_revision", revision},
                          {"executable", executable_digest()},
                          {"provenance", build_provenance()}};
  }();
  nlohmann::json env = cached;
  env["threads"] = worker_threads();
  env["rank"] = rank_info().rank;
  return env;
}

std::string utc_now() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const auto micros = std::chrono::duration_cast<std::chrono::microseconds>(now.time_since_epoch()).count() % 1000000;
  std::tm utc{};
  ::gmtime_r(&seconds, &utc);
  char text[64];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%06lldZ", utc.tm_year + 1900, utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min,
                utc.tm_sec, static_cast<long long>(micros));
  return text;
}

}  // namespace ccd::harness
