// The machine's own thread-scaling ceiling (issue 18): what 1 to N threads can gain on work with no serial part
// and no sharing, so that a strategy's scaling is judged against the machine and not against N. Virtual cores
// (hyperthreads sharing a physical core, or a hypervisor's vCPUs) and a shared memory bus set that ceiling.
//   BM_ComputeBound: independent multiply-add chains in registers, one block per task (no memory traffic);
//   BM_MemoryBound: the STREAM triad a = b + s·c over three 256 MiB arrays (memory bandwidth).
// Each reports items_per_second; the ceiling at N threads is its rate at N over its rate at 1, in one run.

#include "benchmarks/thread_counts.hpp"

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace {

/// Blocks of work, as many as a strategy's parallel loops have (far more than threads), so scheduling is alike.
constexpr std::size_t kBlocks = 1024;

void BM_ComputeBound(benchmark::State& state) {
  const auto threads = static_cast<std::size_t>(state.range(0));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  constexpr int kChains = 8, kSteps = 1 << 16;
  std::vector<double> sink(kBlocks);
  for (auto _ : state) {
    tbb::parallel_for(std::size_t{0}, kBlocks, [&](std::size_t block) {
      double x[kChains];
      for (int c = 0; c < kChains; ++c) x[c] = 1.0 + 1e-9 * static_cast<double>(block * kChains + c);
      for (int s = 0; s < kSteps; ++s) {
        for (int c = 0; c < kChains; ++c) x[c] = x[c] * 0.999999 + 1e-7;
      }
      double sum = 0;
      for (int c = 0; c < kChains; ++c) sum += x[c];
      sink[block] = sum;
    });
    benchmark::DoNotOptimize(sink.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(kBlocks) * kChains * kSteps);
}

void BM_MemoryBound(benchmark::State& state) {
  const auto threads = static_cast<std::size_t>(state.range(0));
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  constexpr std::size_t kCount = std::size_t{256} << 20 >> 3;  // 256 MiB of doubles per array: beyond any L3
  constexpr std::size_t kPerBlock = kCount / kBlocks;
  // Left uninitialised by the allocation and first written by the blocks that use them, with the same static
  // split of blocks over threads as the timed loop: on a machine with several NUMA nodes, pages lie near their
  // thread (the GPU machine has one).
  const std::unique_ptr<double[]> a(new double[kCount]), b(new double[kCount]), c(new double[kCount]);
  tbb::parallel_for(
      std::size_t{0}, kBlocks,
      [&](std::size_t block) {
        for (std::size_t i = block * kPerBlock; i < (block + 1) * kPerBlock; ++i) {
          a[i] = 0.0;
          b[i] = 1.0;
          c[i] = 2.0;
        }
      },
      tbb::static_partitioner());
  for (auto _ : state) {
    tbb::parallel_for(
        std::size_t{0}, kBlocks,
        [&](std::size_t block) {
          for (std::size_t i = block * kPerBlock; i < (block + 1) * kPerBlock; ++i) a[i] = b[i] + 3.0 * c[i];
        },
        tbb::static_partitioner());
    benchmark::DoNotOptimize(a.get());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(kBlocks * kPerBlock));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(kBlocks * kPerBlock * 3 * sizeof(double)));
}

using ccd::benchmarks::thread_counts;

BENCHMARK(BM_ComputeBound)->Apply(thread_counts);
BENCHMARK(BM_MemoryBound)->Apply(thread_counts);

}  // namespace

BENCHMARK_MAIN();
