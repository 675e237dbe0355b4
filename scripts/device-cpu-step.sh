#!/usr/bin/env bash
# The CPU step report's runs on the GPU machine's 16 cores (reports/cpu-step/README.md, issue 18). Builds nothing:
# uses what `CARRY_VARIANTS=... scripts/device-carry.sh` put into device-carry/: ccdbench-NAME for each build
# compared (oldest first, in $VARIANTS), bvh_benchmark and machine_benchmark. Parts ($PARTS):
#   machine: the machine's thread-scaling ceiling (machine_benchmark: compute-bound and memory-bound, 1 to N threads);
#   broad:   the two self-traversal designs on the public steps, 1 to N threads (bvh_benchmark);
#   public:  rod-twist 3036 -> 3037 and cloth-funnel 227 -> 228, `full`, each variant at 1, 2 and N threads
#            (median of $REPEATS passes), then the first and the last variant at 1, 2, 4, 8 and N threads with
#            full, full:filter=on and full+cubic64; --verify none (the answers are compared by their digests,
#            and FullAnswers holds them in CI);
#   filter:  rod-twist, full:filter=on, every variant at 1 and N threads (changes that only the filter sees);
#   paper:   the paper suite, `full`, for $PAPER_VARIANTS (default: the first and last variant): all steps at N
#            threads at the scenes' δ and at δ = 0, and the first $PAPER_STEPS_FEW steps at 1 and 2 threads;
#            --verify none, step digests kept.
# Writes into a work folder and, when $OUT is set, packs it into $OUT/cpu-step.tgz after every part.
# Usage (from the repository root): VARIANTS="before traversal ..." PARTS="machine broad public" scripts/device-cpu-step.sh
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/device-env.sh
out=/tmp/ccdbench-cpu-step
mkdir -p "$out"
pack() { if [ -n "${OUT:-}" ]; then tar czf "$OUT/cpu-step.tgz" -C "$out" .; fi; }
trap pack EXIT
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-/tmp/ccdbench-cache}
export CCDBENCH_DATA_DIR=${CCDBENCH_DATA_DIR:-$PWD/device-carry/data}
PARTS=${PARTS:-machine broad public}
VARIANTS=${VARIANTS:?name the variants, oldest first}
REPEATS=${REPEATS:-3}
PAPER_STEPS_FEW=${PAPER_STEPS_FEW:-5}
threads=$(nproc)
bin=device-carry/bin
first=${VARIANTS%% *}
last=${VARIANTS##* }
PAPER_VARIANTS=${PAPER_VARIANTS:-$first $last}
{ nproc; lscpu | grep -E 'Model name|^CPU\(s\)|Thread|Core|Socket|NUMA node\(s\)|Flags' || true; } > "$out/machine.txt" 2>&1
for v in $VARIANTS; do echo "$v: $("$bin/ccdbench-$v" --version | head -1)"; done >> "$out/machine.txt"
cat "$out/machine.txt"
part() { [[ " $PARTS " == *" $1 "* ]]; }
frames() { echo "$CCDBENCH_DATA_DIR/scalable-ccd-sample/$1/frames/$2.ply $CCDBENCH_DATA_DIR/scalable-ccd-sample/$1/frames/$3.ply"; }
# Thread counts without repeats (N may be 1, 2, 4 or 8 itself).
counts() { printf '%s\n' "$@" | sort -nu | tr '\n' ' '; }
# run VARIANT THREADS NAME ARGS...: one ccdbench run, its table and JSON kept as NAME (its progress and errors in
# NAME.err: a failing run stops the script, and says why there).
run() {
  local variant=$1 t=$2 name=$3
  shift 3
  if ! "$bin/ccdbench-$variant" --threads "$t" run "$@" --out "$out/runs-$name" --json "$out/$name.json" --fresh 2> "$out/$name.err" > "$out/$name.txt"; then
    echo "$name failed:"; tail -n 5 "$out/$name.err"; exit 1
  fi
  gzip -c "$out/runs-$name/results.jsonl" > "$out/$name.jsonl.gz"
  rm -rf "$out/runs-$name"
  echo "$name: $(grep -c '' "$out/$name.txt") lines"
}

if part machine; then
  echo "== machine ceiling"
  "$bin/machine_benchmark" --benchmark_format=json --benchmark_out="$out/machine_benchmark.json" --benchmark_out_format=json | tail -n 12
  pack
fi
if part broad; then
  echo "== broad phase designs"
  "$bin/bvh_benchmark" --benchmark_filter='SelfTraversal|Refit' --benchmark_out="$out/bvh_benchmark.json" --benchmark_out_format=json | grep -E '^BM_'
  pack
fi
if part public; then
  echo "== public steps, every variant"
  for step in "rod-twist 3036 3037" "cloth-funnel 227 228"; do
    set -- $step
    for v in $VARIANTS; do
      for t in $(counts 1 2 "$threads"); do run "$v" "$t" "public-$1-$v-$t" --frames $(frames "$1" "$2" "$3") --strategy full --repeat "$REPEATS" --verify none; done
    done
    pack
  done
  echo "== public steps, thread scaling of the first and last variant"
  for step in "rod-twist 3036 3037" "cloth-funnel 227 228"; do
    set -- $step
    for v in $first $last; do
      for t in $(counts 1 2 4 8 "$threads"); do
        run "$v" "$t" "scaling-$1-$v-$t" --frames $(frames "$1" "$2" "$3") --strategy full,full:filter=on,full+cubic64 --repeat "$REPEATS" --verify none
      done
    done
    pack
  done
fi
if part filter; then
  echo "== rod-twist, full:filter=on, every variant"
  for v in $VARIANTS; do
    for t in $(counts 1 "$threads"); do run "$v" "$t" "filter-rod-twist-$v-$t" --frames $(frames rod-twist 3036 3037) --strategy full:filter=on --repeat "$REPEATS" --verify none; done
  done
  pack
fi
if part paper; then
  echo "== paper suite: $PAPER_VARIANTS"
  for v in $PAPER_VARIANTS; do
    run "$v" "$threads" "paper-$v-$threads-delta" --suite paper --strategy full --verify none
    run "$v" "$threads" "paper-$v-$threads-zero" --suite paper --thickness 0 --strategy full --verify none
    pack
    for t in 1 2; do run "$v" "$t" "paper-$v-$t-delta" --suite paper --max-steps "$PAPER_STEPS_FEW" --strategy full --verify none; done
    pack
  done
fi
echo "done"
