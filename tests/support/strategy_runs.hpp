#pragma once
/// @file
/// Runs a strategy over every step of a frame sequence: what the strategy tests compare.

#include "strategies/strategy.hpp"

#include <tbb/global_control.h>

#include <string>
#include <vector>

namespace ccd::testing {

/// Each step's collision set from strategy `spec` on `threads` threads.
inline std::vector<CollisionSet> run_all_steps(const std::string& spec, const Scene& scene,
                                               const std::vector<std::vector<Vec3>>& frames, std::size_t threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  auto strategy = strategies::make_strategy(spec);
  strategy->init(scene, frames[0]);
  std::vector<CollisionSet> sets;
  for (std::size_t k = 0; k + 1 < frames.size(); ++k) {
    sets.push_back(strategy->step({&scene, k, frames[k], frames[k + 1]}, false).collisions);
  }
  return sets;
}

}  // namespace ccd::testing
