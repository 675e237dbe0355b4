#!/usr/bin/env bash
# Where each millisecond and each byte of an OpenCL step goes (reports/opencl/step/, issue 36), for several builds
# side by side in one invocation: builds nothing; uses what `CARRY_VARIANTS="before=PATH after=PATH ..."
# scripts/device-carry.sh` put into device-carry/ (bin/ccdbench-NAME and the libraries they need). Registers the
# machine's NVIDIA OpenCL driver (installed, not registered). For each part, each variant in turn (same warm
# machine), each of `full:backend=opencl` (conservative) and `full+cubic64:backend=opencl` runs as its own process
# while `nvidia-smi` samples that process's device memory every $SAMPLE_MS ms: the driver's figure beside the
# harness's own count of its buffers (device_bytes). Parts (PARTS, default "tiny public paper large"):
#   tiny:   the ci suite's first 2 steps (scenes of a few hundred triangles): the driver's memory for a context, its
#           kernels and their reservations, which no buffer of ours accounts for;
#   public: rod-twist 3036 -> 3037 and cloth-funnel 227 -> 228, each given as frames A B A B: step 1 is a fresh
#           strategy's first (its lists grow to the step's counts), step 2 (B -> A) has the same swept boxes, so
#           the same candidates and tests, met by lists already sized, and step 3 is step 1 again, warm; $REPEATS
#           passes, each with a fresh strategy;
#   paper:  the paper suite's first $PAPER_STEPS steps at the scenes' δ, and the ci and default suites whole;
#   ball:   the paper's spinning ball whole (resolution 100, 99 steps at the scene's δ: resting contact, issue 51),
#           generated here by the last variant, $BALL_REPEATS passes;
#   large:  the `large` suite's scene (the spinning ball at resolution 708, about 1M triangles, frames 6-9),
#           generated here by the last variant, $LARGE_REPEATS passes.
# Every run is --verify none (the times are the point; the answers are held by the parity tests, the recorded
# answers and the CI gate), and keeps each step's digest: digests equal across variants show the same answers.
# Writes NAME-VARIANT-NARROW.{json,txt,err,smi} into a work folder and, when $OUT is set (the device's return
# folder), packs it into $OUT/opencl-step.tgz after every part. Table: reports/opencl/step/table.py FOLDER.
# Usage (from the repository root, on the GPU machine): PARTS="tiny public" VARIANTS="before after" scripts/device-opencl-step.sh
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/device-env.sh
out=/tmp/ccdbench-opencl-step
source scripts/device-builds.sh
pack() { if [ -n "${OUT:-}" ]; then tar czf "$OUT/opencl-step.tgz" -C "$out" --exclude='./scene-*' --exclude='./runs-*' .; fi; }
trap pack EXIT
PARTS=${PARTS:-tiny public paper large}
VARIANTS=${VARIANTS:-before after}
REPEATS=${REPEATS:-5}
PAPER_STEPS=${PAPER_STEPS:-10}
LARGE_REPEATS=${LARGE_REPEATS:-3}
BALL_REPEATS=${BALL_REPEATS:-3}
SAMPLE_MS=${SAMPLE_MS:-20}
write_machine $VARIANTS
# run VARIANT NAME ARGS...: each GPU strategy in its own process, sampled by nvidia-smi; kept as NAME-VARIANT-NARROW.
run() {
  local variant=$1 name=$2
  shift 2
  for narrow in conservative cubic64; do
    local strategy="full:backend=opencl" stem="$out/$name-$variant-$narrow" start=$SECONDS
    [ "$narrow" = cubic64 ] && strategy="full+cubic64:backend=opencl"
    "$bin/ccdbench-$variant" --threads "$threads" run "$@" --strategy "$strategy" --verify none --out "$out/runs-$name-$variant-$narrow" \
      --json "$stem.json" --fresh 2> "$stem.err" > "$stem.txt" &
    local pid=$!
    nvidia-smi --query-compute-apps=pid,used_memory --format=csv,noheader,nounits -lms "$SAMPLE_MS" 2> /dev/null |
      awk -F', *' -v pid="$pid" '$1 == pid && $2 + 0 > peak {peak = $2 + 0} END {print peak + 0}' > "$stem.smi" &
    local sampler=$!
    if ! wait "$pid"; then
      kill "$sampler" 2> /dev/null || true
      echo "$name-$variant-$narrow failed:"; tail -n 5 "$stem.err"; exit 1
    fi
    pkill -f "nvidia-smi --query-compute-apps" 2> /dev/null || true
    wait "$sampler" 2> /dev/null || true
    gzip -c "$out/runs-$name-$variant-$narrow/results.jsonl" > "$stem.jsonl.gz"
    rm -rf "$out/runs-$name-$variant-$narrow"
    echo "$name-$variant-$narrow: $((SECONDS - start)) s, driver peak $(cat "$stem.smi") MiB"
    grep -E "backend=opencl " "$stem.txt" | head -n 20 || true
  done
}

if part tiny; then
  echo "== tiny: the ci suite's first 2 steps"
  for v in $VARIANTS; do run "$v" tiny --suite ci --max-steps 2; done
  pack
fi
if part public; then
  echo "== public steps"
  for v in $VARIANTS; do
    run "$v" rod-twist --frames $(frames rod-twist 3036 3037) $(frames rod-twist 3036 3037) --repeat "$REPEATS"
    run "$v" cloth-funnel --frames $(frames cloth-funnel 227 228) $(frames cloth-funnel 227 228) --repeat "$REPEATS"
  done
  pack
fi
if part paper; then
  echo "== ci and default suites, paper suite's first $PAPER_STEPS steps"
  for v in $VARIANTS; do
    run "$v" ci --suite ci
    run "$v" default --suite default
    run "$v" paper --suite paper --max-steps "$PAPER_STEPS"
  done
  pack
fi
if part ball; then
  echo "== the paper's spinning ball"
  scene="$out/scene-ball"
  if [ ! -e "$scene/scene.json" ]; then
    start=$SECONDS
    "$bin/ccdbench-${VARIANTS##* }" --threads "$threads" generate spinning-ball --resolution 100 --frames 100 --out "$scene" > "$out/generate-ball.txt"
    echo "generated in $((SECONDS - start)) s"
  fi
  for v in $VARIANTS; do run "$v" ball --scene "$scene" --repeat "$BALL_REPEATS"; done
  pack
fi
if part large; then
  echo "== the large suite's spinning ball"
  scene="$out/scene-large"
  if [ ! -e "$scene/scene.json" ]; then
    start=$SECONDS
    last=${VARIANTS##* }
    "$bin/ccdbench-$last" --threads "$threads" generate spinning-ball --resolution 708 --frames 10 --first-frame 6 --out "$scene" > "$out/generate-large.txt"
    echo "generated in $((SECONDS - start)) s"
  fi
  for v in $VARIANTS; do run "$v" large --scene "$scene" --repeat "$LARGE_REPEATS"; done
  pack
fi
