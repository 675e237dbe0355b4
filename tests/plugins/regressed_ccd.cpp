// The template's method (examples/plugin/my_ccd.cpp) as a user's change might regress it: the same code, except that
// it answers "apart" to the queries whose 24 coordinates hash, with the salt CCDBENCH_TEST_DROP_SALT (default 0), to
// 0 modulo CCDBENCH_TEST_DROP_ONE_IN (default 1000). Each query's answer depends on the query alone (any order, any
// thread, every pass the same), and roughly one query in that many is dropped: the CI round trip of tests/harness/compare_test.cpp tries salts
// until the build misses exactly one pair more than the template, and shows that the gate fails it and compare names
// the pair. Built under the template's plugin name: a rebuild of the user's method, not another method.
#include <ccdbench/ccdbench_plugin.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>

// The template's own entry point is left out (this file makes its own, of the class below).
#pragma push_macro("CCDBENCH_PLUGIN_FROM_CCD_CLASS")
#undef CCDBENCH_PLUGIN_FROM_CCD_CLASS
#define CCDBENCH_PLUGIN_FROM_CCD_CLASS(...)
#include "examples/plugin/my_ccd.cpp"
#undef CCDBENCH_PLUGIN_FROM_CCD_CLASS
#pragma pop_macro("CCDBENCH_PLUGIN_FROM_CCD_CLASS")

namespace {

/// A number from the environment, read once.
std::uint64_t setting(const char* name, std::uint64_t otherwise) {
  const char* text = std::getenv(name);
  return text && *text ? std::strtoull(text, nullptr, 10) : otherwise;
}

std::uint64_t salt() {
  static const std::uint64_t value = setting("CCDBENCH_TEST_DROP_SALT", 0);
  return value;
}

/// One query in this many is dropped (CCDBENCH_TEST_DROP_ONE_IN, default 1000).
std::uint64_t drop_one_in() {
  static const std::uint64_t value = std::max<std::uint64_t>(1, setting("CCDBENCH_TEST_DROP_ONE_IN", 1000));
  return value;
}

/// FNV-1a over the salt and the points' bytes.
bool dropped(std::initializer_list<const ccdbench::Vector3*> points) {
  std::uint64_t hash = 14695981039346656037ULL;
  auto mix = [&](const void* data, std::size_t size) {
    const auto* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t k = 0; k < size; ++k) hash = (hash ^ bytes[k]) * 1099511628211ULL;
  };
  const std::uint64_t s = salt();
  mix(&s, sizeof s);
  for (const ccdbench::Vector3* p : points) mix(p, sizeof *p);
  return hash % drop_one_in() == 0;
}

class RegressedCCD : public MyCCD {
 public:
  bool point_triangle_ccd(const Vector3& p_t0, const Vector3& t0_t0, const Vector3& t1_t0, const Vector3& t2_t0, const Vector3& p_t1,
                          const Vector3& t0_t1, const Vector3& t1_t1, const Vector3& t2_t1, double& toi, double min_distance, double tmax) const {
    if (dropped({&p_t0, &t0_t0, &t1_t0, &t2_t0, &p_t1, &t0_t1, &t1_t1, &t2_t1})) return false;
    return MyCCD::point_triangle_ccd(p_t0, t0_t0, t1_t0, t2_t0, p_t1, t0_t1, t1_t1, t2_t1, toi, min_distance, tmax);
  }
  bool edge_edge_ccd(const Vector3& ea0_t0, const Vector3& ea1_t0, const Vector3& eb0_t0, const Vector3& eb1_t0, const Vector3& ea0_t1,
                     const Vector3& ea1_t1, const Vector3& eb0_t1, const Vector3& eb1_t1, double& toi, double min_distance, double tmax) const {
    if (dropped({&ea0_t0, &ea1_t0, &eb0_t0, &eb1_t0, &ea0_t1, &ea1_t1, &eb0_t1, &eb1_t1})) return false;
    return MyCCD::edge_edge_ccd(ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1, toi, min_distance, tmax);
  }
};

}  // namespace

CCDBENCH_PLUGIN_FROM_CCD_CLASS(RegressedCCD, ccdbench::Vector3, "my-ccd", "0.1",
                               "the template: distance at 33 sample times in double; misses what passes between them",
                               CCDBENCH_THREAD_SAFE | CCDBENCH_REPORTS_TOI)
