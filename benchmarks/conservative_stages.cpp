// Where the conservative narrow phase spends its time, by the stage that decides each pair (issue 51): every pair
// `full` tests on the given steps of a scene, run through this file's own copy of the shared test with its profiling
// hook (CCD_DECIDED_AT, shared/inclusion.h) defined, timed pair by pair beside cubic64. Prints per stage the pairs,
// their share of the time, the sub-boxes the search examined and what collides; and, for the pairs the search
// decides, how far apart they are at the step's ends against δ. A profile, not a benchmark: the times are for
// comparing stages within one run.
// With --slow N DIR it profiles nothing: it writes the pairs whose search examines more than N sub-boxes to
// DIR/vertex-face/slow.csv and DIR/edge-edge/slow.csv (rational query files, no truth: `ccdbench queries` scores
// them), keeping nothing else, so that a step of a million triangles fits in memory.
// --sample K profiles every K-th pair only (a step of a million triangles has some 5e8).
// Usage: conservative_stages SCENE [--thickness D] [--steps FIRST LAST EVERY] [--slow N DIR] [--sample K]

#include <cstddef>

namespace profile {
/// Where the last test ended, and how many sub-boxes its search examined.
struct Ended {
  int stage = -1;
  long iterations = 0;
};
thread_local Ended ended;
inline void record(int stage, int) { ended = {stage, 0}; }
template <class Search>
void record(int stage, const Search* search) {
  ended = {stage, search->iterations};
}
}  // namespace profile
#define CCD_DECIDED_AT(stage, search) ::profile::record((stage), (search))

#include "core/number_text.hpp"
#include "core/step.hpp"
#include "datasets/query_file.hpp"
#include "datasets/scene_file.hpp"
#include "strategies/narrowphase/round_to_nearest.hpp"
#include "strategies/narrowphase/shared.hpp"
#include "strategies/registry.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace ccd;
namespace sh = ccd::narrowphase::shared::f64;

/// cubic64's default eta (strategies/narrowphase/cubic.cpp).
constexpr double kCubicEta = 1e-6;
/// conservative's defaults (tolerance, toi_tolerance, max_iterations), as `full` runs it.
constexpr double kTolerance = 1e-10, kToiTolerance = 1e-6;
constexpr long kMaxIterations = 20000;

struct PairRun {
  int stage = -1;
  long iterations = 0;
  bool collides = false;
  double ns = 0, cubic_ns = 0;
  double start_over_delta = 0, end_over_delta = 0;  // distance at t = 0 and 1 over δ
  bool normal_separates = false;                    // the whole step, along X × Y at t = 0 or 1 (either sign)
  bool vertex_face = false;
  double least_over_delta = 0;  // the least distance over 257 sampled times, over δ (stage 4 only)
  double toi = 0;
  /// For a searched pair that collides: the TOI less the earliest time a separating plane along the normal X × Y
  /// (at t = 0, at t = 1, at the TOI) allows a contact (each n·F linear in t over the whole step), in steps; NaN
  /// where that plane does not separate at t = 0.
  double plane_gap[3] = {NAN, NAN, NAN};
};

/// The earliest time in [0, 1] at which a plane along `n` (either sign) no longer keeps every corner value of F,
/// over the whole (u, v) domain, more than δ|n| from 0; NaN when it does not at t = 0. Exact arithmetic assumed:
/// a measurement, not a certified bound.
double plane_release(const sh::ccd_inclusion& search, sh::ccd_v3 n) {
  const double reach = search.thickness * sh::ccd_norm(n);
  sh::ccd_v3 at0[2 * CCD_CLIPPED_VERTICES], at1[2 * CCD_CLIPPED_VERTICES];
  const sh::ccd_sub_box start = sh::ccd_sub_box_make(0, 0, 0, 1, 0, 1, 0), end = sh::ccd_sub_box_make(1, 1, 0, 1, 0, 1, 0);
  const int count = sh::ccd_box_values(&search, &start, at0);
  sh::ccd_box_values(&search, &end, at1);
  for (double sign : {1.0, -1.0}) {
    double release = 1;
    bool separated = true;
    for (int i = 0; i < count; ++i) {
      const double g0 = sign * sh::ccd_dot(n, at0[i]) - reach, g1 = sign * sh::ccd_dot(n, at1[i]) - reach;
      if (!(g0 > 0)) separated = false;
      if (g1 < 0) release = std::min(release, g0 / (g0 - g1));
    }
    if (separated) return release;
  }
  return NAN;
}

/// Whether the whole step's F values are separated from the δ-ball along the normal X × Y at t = 0 or at t = 1.
bool normal_separates(const sh::ccd_v3 rows[8], double thickness, bool vertex_face) {
  sh::ccd_v3 scaled[8];
  for (int i = 0; i < 8; ++i) scaled[i] = rows[i];
  double delta = thickness;
  int exponent = 0;
  if (!sh::ccd_scale_to_unit(scaled, &delta, &exponent)) return false;
  sh::ccd_inclusion search;
  sh::ccd_inclusion_init(&search, scaled, delta, vertex_face, kTolerance, kToiTolerance, kMaxIterations);
  const sh::ccd_sub_box root = sh::ccd_sub_box_make(0, 1, 0, 1, 0, 1, 0);
  sh::ccd_v3 values[2 * CCD_CLIPPED_VERTICES];
  const int count = sh::ccd_box_values(&search, &root, values);
  for (const sh::ccd_v3* x : {search.x0, search.x1}) {
    sh::ccd_v3 S, X, Y;
    sh::ccd_split_terms(&search, x, &S, &X, &Y);
    const sh::ccd_v3 n = sh::ccd_cross(X, Y);
    if (sh::ccd_separated_along(&search, values, count, n) || sh::ccd_separated_along(&search, values, count, sh::ccd_scale(-1.0, n))) return true;
  }
  return false;
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// This file's copy of the conservative test of one pair (rescaled rows; the caller holds round-to-nearest), with
/// room for any search; profile::ended says where it ended.
sh::ccd_conservative_outcome conservative_test(const sh::ccd_v3* rows, double thickness, bool vertex_face) {
  static thread_local std::vector<sh::ccd_sub_box> storage(1 << 16);
  return sh::ccd_conservative_test(rows, thickness, vertex_face, kTolerance, kToiTolerance, kMaxIterations, 0, storage.data(),
                                   static_cast<int>(storage.size()));
}

/// Every elementary pair `full` tests on steps first, first + every, ... below last, every `sample`-th of them
/// handed to visit(rows, vertex_face).
template <class Visit>
void for_each_tested_pair(const datasets::SceneSequence& sequence, const Scene& scene, std::size_t first, std::size_t last, std::size_t every,
                          std::size_t sample, Visit&& visit) {
  for (std::size_t k = first; k < last; k += every) {
    const std::vector<Vec3> x0 = sequence.frame(k), x1 = sequence.frame(k + 1);
    auto full = strategies::make_strategy("full");
    full->init(scene, x0);
    const strategies::StepResult result = full->step({&scene, k, x0, x1}, true);
    std::size_t index = 0;
    for (const VertexFacePair& p : result.tested->vertex_face) {
      if (index++ % sample == 0) visit(pair_rows(scene.topology(), x0, x1, p), true);
    }
    for (const EdgeEdgePair& p : result.tested->edge_edge) {
      if (index++ % sample == 0) visit(pair_rows(scene.topology(), x0, x1, p), false);
    }
  }
}

PairRun run_pair(const std::array<Vec3, 8>& original, double thickness, bool vertex_face) {
  const narrowphase::RoundToNearest rounding;
  const auto rows = narrowphase::shared::to_shared_rows(original);
  PairRun run;
  auto start = std::chrono::steady_clock::now();
  const sh::ccd_conservative_outcome outcome = conservative_test(rows.data(), thickness, vertex_face);
  run.ns = seconds_since(start) * 1e9;
  run.stage = profile::ended.stage;
  run.iterations = profile::ended.iterations;
  run.collides = outcome.collides != 0;
  run.toi = outcome.toi;
  start = std::chrono::steady_clock::now();
  volatile int cubic = sh::ccd_cubic_test(rows.data(), thickness, kCubicEta, vertex_face).collides;
  (void)cubic;
  run.cubic_ns = seconds_since(start) * 1e9;
  sh::ccd_v3 at_end[8];
  for (int i = 0; i < 4; ++i) at_end[i] = at_end[i + 4] = rows[static_cast<std::size_t>(i) + 4];
  const double delta = thickness > 0 ? thickness : 1.0;
  run.start_over_delta = std::sqrt(sh::ccd_pair_squared_distance(rows.data(), vertex_face)) / delta;
  run.end_over_delta = std::sqrt(sh::ccd_pair_squared_distance(at_end, vertex_face)) / delta;
  if (run.stage >= 2) run.normal_separates = normal_separates(rows.data(), thickness, vertex_face);
  run.vertex_face = vertex_face;
  if (run.stage == 4) {
    double least = INFINITY;
    for (int i = 0; i <= 256; ++i) {
      const double t = i / 256.0;
      sh::ccd_v3 at[4];
      for (int k = 0; k < 4; ++k)
        at[k] = sh::ccd_add(rows[static_cast<std::size_t>(k)],
                            sh::ccd_scale(t, sh::ccd_sub(rows[static_cast<std::size_t>(k) + 4], rows[static_cast<std::size_t>(k)])));
      least = std::min(least, std::sqrt(sh::ccd_pair_squared_distance(at, vertex_face)));
    }
    run.least_over_delta = least / delta;
    if (run.collides) {
      sh::ccd_v3 scaled[8];
      for (int i = 0; i < 8; ++i) scaled[i] = rows[static_cast<std::size_t>(i)];
      double d = thickness;
      int exponent = 0;
      if (sh::ccd_scale_to_unit(scaled, &d, &exponent)) {
        sh::ccd_inclusion search;
        sh::ccd_inclusion_init(&search, scaled, d, vertex_face, kTolerance, kToiTolerance, kMaxIterations);
        const double times[3] = {0, 1, run.toi};
        for (int k = 0; k < 3; ++k) {
          sh::ccd_v3 S, X, Y;
          sh::ccd_terms_at(&search, times[k], &S, &X, &Y);
          run.plane_gap[k] = run.toi - plane_release(search, sh::ccd_cross(X, Y));
        }
      }
    }
  }
  return run;
}

/// --slow: the pairs whose search examines more than `over` sub-boxes, as query files; prints each one's count.
int write_slow_pairs(const datasets::SceneSequence& sequence, const Scene& scene, std::size_t first, std::size_t last, std::size_t every, long over,
                     const std::filesystem::path& dir) {
  std::vector<datasets::Query> slow[2];
  std::size_t pairs = 0;
  for_each_tested_pair(sequence, scene, first, last, every, 1, [&](const std::array<Vec3, 8>& rows, bool vertex_face) {
    const narrowphase::RoundToNearest rounding;
    conservative_test(narrowphase::shared::to_shared_rows(rows).data(), scene.thickness(), vertex_face);
    ++pairs;
    if (profile::ended.iterations <= over) return;
    std::printf("%s pair, stage %d, %ld sub-boxes\n", vertex_face ? "VF" : "EE", profile::ended.stage, profile::ended.iterations);
    slow[vertex_face ? 0 : 1].push_back(datasets::query_of_doubles(rows));
  });
  std::printf("%zu pairs, %zu VF and %zu EE over %ld sub-boxes\n", pairs, slow[0].size(), slow[1].size(), over);
  std::filesystem::create_directories(dir / "vertex-face");
  std::filesystem::create_directories(dir / "edge-edge");
  datasets::write_query_file(dir / "vertex-face" / "slow.csv", slow[0]);
  datasets::write_query_file(dir / "edge-edge" / "slow.csv", slow[1]);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: conservative_stages SCENE [--thickness D] [--steps FIRST LAST EVERY] [--slow N DIR] [--sample K]\n");
    return 2;
  }
  datasets::SceneSequence sequence = datasets::load_scene_file(argv[1]);
  std::size_t first = 0, last = sequence.num_steps(), every = 1;
  double thickness = sequence.scene().thickness();
  long slow_over = -1;
  std::size_t sample = 1;
  std::filesystem::path slow_dir;
  for (int a = 2; a < argc; ++a) {
    const std::string flag = argv[a];
    // Numbers as the project reads them (core/number_text.hpp, whatever the C locale); a bad one ends the run.
    const auto number = [&](const char* what) {
      const std::optional<double> value = parse_double(argv[++a]);
      if (!value || !(*value >= 0)) {
        std::fprintf(stderr, "command line:%s: %s is not a number >= 0\n", what, argv[a]);
        std::exit(2);
      }
      return *value;
    };
    if (flag == "--thickness" && a + 1 < argc) thickness = number("--thickness");
    if (flag == "--sample" && a + 1 < argc) sample = std::max<std::size_t>(1, static_cast<std::size_t>(number("--sample")));
    if (flag == "--slow" && a + 2 < argc) {
      slow_over = static_cast<long>(number("--slow"));
      slow_dir = argv[++a];
    }
    if (flag == "--steps" && a + 3 < argc) {
      first = static_cast<std::size_t>(number("--steps"));
      last = std::min<std::size_t>(static_cast<std::size_t>(number("--steps")), sequence.num_steps());
      every = std::max<std::size_t>(1, static_cast<std::size_t>(number("--steps")));
    }
  }
  const Scene scene = sequence.scene().with_thickness(thickness);
  if (slow_over >= 0) return write_slow_pairs(sequence, scene, first, last, every, slow_over, slow_dir);
  std::vector<PairRun> runs;
  for_each_tested_pair(sequence, scene, first, last, every, sample,
                       [&](const std::array<Vec3, 8>& rows, bool vertex_face) { runs.push_back(run_pair(rows, thickness, vertex_face)); });
  double total = 0, cubic_total = 0;
  for (const PairRun& r : runs) {
    total += r.ns;
    cubic_total += r.cubic_ns;
  }
  if (sample > 1) std::printf("(every %zu-th pair)\n", sample);
  std::printf("%s, δ = %g, steps %zu..%zu every %zu: %zu pairs, conservative %.1f ms, cubic64 %.1f ms (%.2fx)\n", argv[1], thickness, first, last,
              every, runs.size(), total / 1e6, cubic_total / 1e6, total / cubic_total);
  const char* names[] = {"0 within δ at t = 0",
                         "1 whole domain excluded",
                         "2 no time window",
                         "3 contact proven (t = 0 or near t0)",
                         "4 search",
                         "5 advancement passed every window"};
  std::printf("%-36s %10s %8s %8s %10s %10s %10s %10s\n", "stage", "pairs", "time %", "ns/pair", "iter mean", "iter p50", "iter p99", "collide");
  for (int stage = 0; stage <= 5; ++stage) {
    std::vector<long> iterations;
    double ns = 0;
    std::size_t collide = 0;
    for (const PairRun& r : runs) {
      if (r.stage != stage) continue;
      iterations.push_back(r.iterations);
      ns += r.ns;
      collide += r.collides;
    }
    if (iterations.empty()) continue;
    std::sort(iterations.begin(), iterations.end());
    double mean = 0;
    for (long i : iterations) mean += static_cast<double>(i);
    mean /= static_cast<double>(iterations.size());
    std::printf("%-36s %10zu %8.1f %8.0f %10.1f %10ld %10ld %10zu\n", names[stage], iterations.size(), 100 * ns / total,
                ns / static_cast<double>(iterations.size()), mean, iterations[iterations.size() / 2], iterations[iterations.size() * 99 / 100],
                collide);
  }
  // What a test along the normal X × Y (at t = 0 or 1) over the whole step would have excluded, by stage.
  std::printf("\nseparated along the normal at t = 0 or 1 (whole step), by stage: pairs, their time %%\n");
  for (int stage = 2; stage <= 5; ++stage) {
    std::size_t count = 0, wrong = 0;
    double ns = 0;
    for (const PairRun& r : runs) {
      if (r.stage != stage || !r.normal_separates) continue;
      ++count;
      ns += r.ns;
      wrong += r.collides;
    }
    std::printf("  stage %d: %zu pairs, %.1f%% of the time%s\n", stage, count, 100 * ns / total, wrong ? " (SOME COLLIDE: unsound)" : "");
  }
  // The search's pairs that do not collide, by kind and by how close they come (sampled) over δ.
  std::printf("\nsearch (stage 4) pairs that do not collide, by kind and least sampled distance over δ: pairs, time %%, iterations mean\n");
  const double margins[] = {1, 1.0001, 1.001, 1.01, 1.1, 1.5, 1e300};
  for (int kind = 0; kind < 2; ++kind) {
    for (int m = 0; m + 1 < 7; ++m) {
      std::size_t count = 0;
      double ns = 0, iterations = 0;
      for (const PairRun& r : runs) {
        if (r.stage != 4 || r.collides || r.vertex_face != (kind == 0) || r.least_over_delta < margins[m] || r.least_over_delta >= margins[m + 1])
          continue;
        ++count;
        ns += r.ns;
        iterations += static_cast<double>(r.iterations);
      }
      if (count)
        std::printf("  %s least/δ [%g, %g): %6zu pairs %5.1f%% %8.1f it\n", kind == 0 ? "VF" : "EE", margins[m], margins[m + 1], count,
                    100 * ns / total, iterations / static_cast<double>(count));
    }
  }
  // For the searched pairs that collide: how far before the TOI a plane along the normal lets a contact happen.
  std::printf("\nsearch (stage 4) pairs that collide: TOI less the time a plane along X × Y stops separating (steps)\n");
  const char* at[] = {"t = 0", "t = 1", "the TOI"};
  for (int k = 0; k < 3; ++k) {
    std::vector<double> gaps;
    std::size_t none = 0;
    for (const PairRun& r : runs) {
      if (r.stage != 4 || !r.collides) continue;
      if (std::isnan(r.plane_gap[k])) {
        ++none;
      } else {
        gaps.push_back(r.plane_gap[k]);
      }
    }
    std::sort(gaps.begin(), gaps.end());
    const auto q = [&](double f) {
      return gaps.empty() ? std::numeric_limits<double>::quiet_NaN() : gaps[static_cast<std::size_t>(f * static_cast<double>(gaps.size() - 1))];
    };
    std::size_t within = 0;
    for (double g : gaps) within += g >= 0 && g <= 1e-6;
    std::printf("  normal at %-8s: %zu separate at t = 0 (%zu do not); gap min %.3g, p50 %.3g, p90 %.3g, max %.3g; within 1e-6: %zu\n", at[k],
                gaps.size(), none, q(0), q(0.5), q(0.9), q(1), within);
  }
  // The search's pairs by their distance at the step's ends, over δ: resting contact is within a few δ at both.
  std::printf("\nsearch (stage 4) by distance at t = 0 and t = 1 over δ: pairs, time %%, iterations mean, collide\n");
  const double edges[] = {0, 1, 1.5, 2, 4, 1e300};
  for (int a = 0; a < 5; ++a) {
    for (int b = 0; b < 5; ++b) {
      std::size_t count = 0, collide = 0;
      double ns = 0, iterations = 0;
      for (const PairRun& r : runs) {
        if (r.stage != 4 || r.start_over_delta < edges[a] || r.start_over_delta >= edges[a + 1] || r.end_over_delta < edges[b] ||
            r.end_over_delta >= edges[b + 1])
          continue;
        ++count;
        collide += r.collides;
        ns += r.ns;
        iterations += static_cast<double>(r.iterations);
      }
      if (count == 0) continue;
      std::printf("  d0/δ [%g, %g) d1/δ [%g, %g): %8zu pairs %6.1f%% %8.1f it %7zu collide\n", edges[a], edges[a + 1], edges[b], edges[b + 1], count,
                  100 * ns / total, iterations / static_cast<double>(count), collide);
    }
  }
  return 0;
}
