// Face-shape pairs (strategies/face_shape.hpp): what each stage of the strategies' decision costs per pair, and
// what libccd adds to the cull, on seeded random faces near a sphere's or a box's surface (a face within half a
// shape size of it, moving about a third of a size: the pairs a broad phase hands over). In one invocation:
//   cull            libccd's GJK, then a certified axis where GJK says apart (what the strategies run)
//   certified_only  the certified axes on every pair, without libccd
//   cull_narrow     the cull, then the conservative narrow phase on the survivors (the strategies' whole decision)
//   cull_narrow_no_prefilter  the same without the box's per-pair box test (narrow_phase_face_shape's
//                   box_prefilter), to attribute it
//   narrow_only     the conservative narrow phase on every pair, without a cull
//   reference       the exact decision (reference/face_shape.hpp)
// Counters: culled (fraction of pairs culled), colliding (fraction the narrow phase calls colliding).

#include "reference/face_shape.hpp"
#include "strategies/face_shape.hpp"
#include "strategies/narrowphase_registry.hpp"

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

namespace ccd {
namespace {

constexpr std::uint64_t kSeed = 20261123;
constexpr int kPairs = 512;
constexpr double kThickness = 0.01;

struct Pairs {
  Shape shape;
  std::vector<FaceShapeRows> rows;
};

/// kPairs faces near a unit-sized shape at the origin (seed kSeed), the shape moving too.
Pairs make_pairs(ShapeKind kind) {
  std::mt19937_64 random(kSeed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Pairs pairs;
  pairs.shape = kind == ShapeKind::sphere ? Shape{kind, 0.8, Vec3::Zero()} : Shape{kind, 0.0, Vec3(0.9, 0.6, 0.75)};
  for (int n = 0; n < kPairs; ++n) {
    FaceShapeRows rows;
    rows.centre_t0 = Vec3::Zero();
    rows.centre_t1 = Vec3(unit(random), unit(random), unit(random)) * 0.1;
    const Vec3 direction = Vec3(unit(random), unit(random), unit(random)).normalized();
    const Vec3 anchor = direction * (1.0 + 0.5 * unit(random));
    const Vec3 motion = Vec3(unit(random), unit(random), unit(random)) * 0.3;
    for (int i = 0; i < 3; ++i) {
      rows.face_t0[i] = anchor + Vec3(unit(random), unit(random), unit(random)) * 0.1;
      rows.face_t1[i] = rows.face_t0[i] + motion;
    }
    pairs.rows.push_back(rows);
  }
  return pairs;
}

const Pairs& pairs_of(ShapeKind kind) {
  static const Pairs sphere = make_pairs(ShapeKind::sphere), box = make_pairs(ShapeKind::box);
  return kind == ShapeKind::sphere ? sphere : box;
}

const narrowphase::NarrowPhase& conservative() {
  static const auto narrow = narrowphase::make_narrow_phase("conservative");
  return *narrow;
}

enum class Stage { cull, certified_only, cull_narrow, cull_narrow_no_prefilter, narrow_only, reference };

void BM_FaceShape(benchmark::State& state, ShapeKind kind, Stage stage) {
  const Pairs& pairs = pairs_of(kind);
  std::size_t culled = 0, colliding = 0, decided = 0;
  for (auto _ : state) {
    for (const FaceShapeRows& rows : pairs.rows) {
      ++decided;
      switch (stage) {
        case Stage::cull:
        case Stage::certified_only: {
          const bool apart =
              strategies::cull_face_shape(pairs.shape, rows, kThickness, stage == Stage::cull) == strategies::FaceShapeCull::certified_apart;
          culled += apart ? 1 : 0;
          break;
        }
        case Stage::cull_narrow:
        case Stage::cull_narrow_no_prefilter: {
          if (strategies::cull_face_shape(pairs.shape, rows, kThickness) == strategies::FaceShapeCull::certified_apart) {
            ++culled;
            break;
          }
          const bool prefilter = stage == Stage::cull_narrow;
          colliding += strategies::narrow_phase_face_shape(conservative(), pairs.shape, rows, kThickness, prefilter).collides ? 1 : 0;
          break;
        }
        case Stage::narrow_only:
          colliding += strategies::narrow_phase_face_shape(conservative(), pairs.shape, rows, kThickness).collides ? 1 : 0;
          break;
        case Stage::reference: colliding += reference::decide_face_shape(pairs.shape, rows, kThickness).collides ? 1 : 0; break;
      }
    }
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(decided));
  state.counters["culled"] = static_cast<double>(culled) / static_cast<double>(decided);
  state.counters["colliding"] = static_cast<double>(colliding) / static_cast<double>(decided);
}

void register_all() {
  for (const ShapeKind kind : {ShapeKind::sphere, ShapeKind::box}) {
    for (const auto& [stage, name] :
         {std::pair{Stage::cull, "cull"}, std::pair{Stage::certified_only, "certified_only"}, std::pair{Stage::cull_narrow, "cull_narrow"},
          std::pair{Stage::cull_narrow_no_prefilter, "cull_narrow_no_prefilter"}, std::pair{Stage::narrow_only, "narrow_only"},
          std::pair{Stage::reference, "reference"}}) {
      benchmark::RegisterBenchmark(("FaceShape/" + std::string(to_string(kind)) + "/" + name).c_str(), [kind, stage](benchmark::State& state) {
        BM_FaceShape(state, kind, stage);
      })->Unit(benchmark::kMicrosecond);
    }
  }
}

const bool kRegistered = (register_all(), true);

}  // namespace
}  // namespace ccd

BENCHMARK_MAIN();
