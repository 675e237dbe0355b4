#pragma once
/// @file
/// Thread counts for benchmarks that measure scaling: 1, 2, 4, ... up to the threads TBB may use here (which
/// honours the process's CPU affinity, as `nproc` does, where std::thread::hardware_concurrency counts every CPU of
/// the host).

#include <benchmark/benchmark.h>
#include <tbb/info.h>

#include <algorithm>

namespace ccd::benchmarks {

inline void thread_counts(benchmark::internal::Benchmark* b) {
  const int cores = std::max(1, tbb::info::default_concurrency());
  for (int t = 1; t < cores; t *= 2) b->Arg(t);
  b->Arg(cores);
  b->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();
}

}  // namespace ccd::benchmarks
