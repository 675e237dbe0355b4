#!/usr/bin/env bash
# Runs the coverage-guided fuzz targets (libFuzzer, clang from Debian) on the readers of PLY, OBJ, CSV queries,
# scene files and the truth cache, each for SECONDS (default 60), one after the other.
# Usage: scripts/fuzz.sh [SECONDS] [--merge]
#   New inputs go to build/fuzz/corpus/TARGET, crashes to build/fuzz/crashes/TARGET. With --merge, the inputs that
#   add coverage are merged into tests/fuzz/corpus/TARGET, which ctest replays in every build (commit them).
# Each input may allocate at most 1 GiB and run 10 s: a reader that allocates from an unbacked count, or loops on
# one, is a finding like a crash.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
merge=${2:-}
scripts/setup.sh clang-14 libclang-rt-14-dev
cmake --preset fuzz >/dev/null
targets=(ply obj query_csv scene_file truth_cache)
cmake --build --preset fuzz -j "$(nproc)" --target "${targets[@]/#/fuzz_}"
status=0
for target in "${targets[@]}"; do
  corpus=build/fuzz/corpus/$target crashes=build/fuzz/crashes/$target
  mkdir -p "$corpus" "$crashes"
  echo "fuzz: $target for $seconds s"
  if ! "build/fuzz/bin/fuzz_$target" "$corpus" "tests/fuzz/corpus/$target" -max_total_time="$seconds" -timeout=10 \
      -rss_limit_mb=2048 -malloc_limit_mb=1024 -max_len=4096 -print_final_stats=1 -artifact_prefix="$crashes/" \
      2> "build/fuzz/$target.log"; then
    echo "fuzz: $target FOUND A CRASH: build/fuzz/$target.log, inputs in $crashes" >&2
    status=1
  fi
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb|cov: " "build/fuzz/$target.log" | tail -3 || true
  if [[ $merge == --merge ]]; then
    "build/fuzz/bin/fuzz_$target" -merge=1 "tests/fuzz/corpus/$target" "$corpus" 2>> "build/fuzz/$target.log"
  fi
done
exit $status
