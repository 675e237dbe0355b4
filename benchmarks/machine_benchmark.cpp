// The machine's own thread-scaling ceiling (issue 18): what 1 to N threads can gain on work with no serial part
// and no sharing, so that a strategy's scaling is judged against the machine and not against N. Virtual cores
// (hyperthreads sharing a physical core, or a hypervisor's vCPUs) and a shared memory bus set that ceiling.
//   BM_ComputeBound: independent multiply-add chains in registers, one block per task (no memory traffic);
//   BM_MemoryBound: the STREAM triad a = b + s·c over three 256 MiB arrays (memory bandwidth).
// Each reports items_per_second; the ceiling at N threads is its rate at N over its rate at 1, in one run.

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <thread>
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
  std::vector<double> a(kCount), b(kCount, 1.0), c(kCount, 2.0);
  const std::size_t per_block = kCount / kBlocks;
  // First touch by the same blocks, so pages lie where their threads run (NUMA).
  tbb::parallel_for(std::size_t{0}, kBlocks, [&](std::size_t block) {
    std::fill(a.begin() + static_cast<std::ptrdiff_t>(block * per_block), a.begin() + static_cast<std::ptrdiff_t>((block + 1) * per_block), 0.0);
  });
  for (auto _ : state) {
    tbb::parallel_for(std::size_t{0}, kBlocks, [&](std::size_t block) {
      for (std::size_t i = block * per_block; i < (block + 1) * per_block; ++i) a[i] = b[i] + 3.0 * c[i];
    });
    benchmark::DoNotOptimize(a.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(kBlocks * per_block));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(kBlocks * per_block * 3 * sizeof(double)));
}

/// Threads 1, 2, 4, ... up to the machine's.
void thread_counts(benchmark::internal::Benchmark* b) {
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (int t = 1; t < cores; t *= 2) b->Arg(t);
  b->Arg(cores);
  b->ArgName("threads")->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(BM_ComputeBound)->Apply(thread_counts);
BENCHMARK(BM_MemoryBound)->Apply(thread_counts);

}  // namespace

BENCHMARK_MAIN();
