// The template's method (examples/plugin/my_ccd.cpp) as a change might slow it down: the same answers, every call
// taking CCDBENCH_TEST_SLOWDOWN times as long (default 1.25; it spins after the call for the time the call took times
// the factor less one). What the time verdict of `compare` must flag (scripts/time-verdicts.sh counts how often it
// does, and how often it flags two runs of the same code). Built under the template's plugin name: a rebuild of the
// user's method, not another method.
#include <ccdbench/ccdbench_plugin.hpp>

#include <chrono>
#include <cstdlib>

// The template's own entry point is left out (this file makes its own, of the class below).
#pragma push_macro("CCDBENCH_PLUGIN_FROM_CCD_CLASS")
#undef CCDBENCH_PLUGIN_FROM_CCD_CLASS
#define CCDBENCH_PLUGIN_FROM_CCD_CLASS(...)
#include "examples/plugin/my_ccd.cpp"
#undef CCDBENCH_PLUGIN_FROM_CCD_CLASS
#pragma pop_macro("CCDBENCH_PLUGIN_FROM_CCD_CLASS")

namespace {

/// The factor every call's time is multiplied by, read once.
double slowdown() {
  static const double factor = [] {
    const char* text = std::getenv("CCDBENCH_TEST_SLOWDOWN");
    return text && *text ? std::atof(text) : 1.25;
  }();
  return factor;
}

/// Runs `call`, then spins until it has taken slowdown() times its own time.
template <class Call>
bool slowed(Call&& call) {
  const auto start = std::chrono::steady_clock::now();
  const bool answer = call();
  const auto took = std::chrono::steady_clock::now() - start;
  const auto until = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(took * slowdown());
  while (std::chrono::steady_clock::now() < until) {
  }
  return answer;
}

class SlowedCCD : public MyCCD {
 public:
  bool point_triangle_ccd(const Vector3& p_t0, const Vector3& t0_t0, const Vector3& t1_t0, const Vector3& t2_t0, const Vector3& p_t1,
                          const Vector3& t0_t1, const Vector3& t1_t1, const Vector3& t2_t1, double& toi, double min_distance, double tmax) const {
    return slowed([&] { return MyCCD::point_triangle_ccd(p_t0, t0_t0, t1_t0, t2_t0, p_t1, t0_t1, t1_t1, t2_t1, toi, min_distance, tmax); });
  }
  bool edge_edge_ccd(const Vector3& ea0_t0, const Vector3& ea1_t0, const Vector3& eb0_t0, const Vector3& eb1_t0, const Vector3& ea0_t1,
                     const Vector3& ea1_t1, const Vector3& eb0_t1, const Vector3& eb1_t1, double& toi, double min_distance, double tmax) const {
    return slowed([&] { return MyCCD::edge_edge_ccd(ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1, toi, min_distance, tmax); });
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(SlowedCCD, ccdbench::Vector3, "my-ccd", "0.1",
                               "the template: distance at 33 sample times in double; misses what passes between them",
                               CCDBENCH_THREAD_SAFE | CCDBENCH_REPORTS_TOI)
