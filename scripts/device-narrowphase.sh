#!/usr/bin/env bash
# The narrow phase's step tables on the GPU machine (reports/narrowphase/device/, issue 35), before and after, from
# one invocation: builds nothing; uses what `CARRY_VARIANTS="before=PATH after=PATH" scripts/device-carry.sh` put
# into device-carry/ (bin/ccdbench-before, bin/ccdbench-after and the libraries they need). Registers the machine's
# NVIDIA OpenCL driver (installed, not registered), then for each variant, one after the other on the same warm
# machine, `full` (conservative) and `full+cubic64` on the CPU (every core) and on the GPU (backend=opencl):
#   public: rod-twist 3036 -> 3037 and cloth-funnel 227 -> 228, median of $REPEATS passes;
#   paper:  the paper suite's first $PAPER_STEPS steps at the scenes' δ;
#   large:  the `large` suite's scene (the spinning ball at resolution 708, about 1M triangles, frames 6-9: 3 steps
#           of contact), generated here by the newest variant so that older builds run it too, every
#           step, $LARGE_REPEATS pass(es).
# Every run is --verify none: the times are the point here; the answers are held by the tests (the parity of the two
# backends, the recorded answers and the CI gate), and each step's digest is kept to compare them.
# PARTS chooses among "public paper large" (default: all). Writes every table and JSON summary to a work folder and,
# when $OUT is set (the device's return folder), packs it into $OUT/narrowphase-device.tgz after every part.
# Usage (from the repository root): scripts/device-narrowphase.sh
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/device-env.sh
out=/tmp/ccdbench-narrowphase
source scripts/device-builds.sh
pack() { if [ -n "${OUT:-}" ]; then tar czf "$OUT/narrowphase-device.tgz" -C "$out" --exclude='./scene-*' .; fi; }
trap pack EXIT
PARTS=${PARTS:-public paper large}
VARIANTS=${VARIANTS:-before after}
REPEATS=${REPEATS:-5}
PAPER_STEPS=${PAPER_STEPS:-10}
LARGE_REPEATS=${LARGE_REPEATS:-1}
strategies="full,full+cubic64,full:backend=opencl,full+cubic64:backend=opencl"
write_machine $VARIANTS
# run VARIANT NAME ARGS...: one ccdbench run on every core, its table and JSON kept as NAME-VARIANT.
run() {
  local variant=$1 name=$2
  shift 2
  local start=$SECONDS
  if ! "$bin/ccdbench-$variant" --threads "$threads" run "$@" --strategy "$strategies" --verify none \
       --out "$out/runs-$name-$variant" --json "$out/$name-$variant.json" --fresh 2> "$out/$name-$variant.err" > "$out/$name-$variant.txt"; then
    echo "$name-$variant failed:"; tail -n 5 "$out/$name-$variant.err"; exit 1
  fi
  gzip -c "$out/runs-$name-$variant/results.jsonl" > "$out/$name-$variant.jsonl.gz"
  rm -rf "$out/runs-$name-$variant"
  echo "$name-$variant: $((SECONDS - start)) s"
  cat "$out/$name-$variant.txt"
}

if part public; then
  echo "== public steps"
  for v in $VARIANTS; do
    run "$v" rod-twist --frames $(frames rod-twist 3036 3037) --repeat "$REPEATS"
    run "$v" cloth-funnel --frames $(frames cloth-funnel 227 228) --repeat "$REPEATS"
  done
  pack
fi
if part paper; then
  echo "== paper suite, first $PAPER_STEPS steps"
  for v in $VARIANTS; do run "$v" paper --suite paper --max-steps "$PAPER_STEPS" --repeat 3; done
  pack
fi
if part large; then
  echo "== the large suite's spinning ball"
  scene="$out/scene-large"
  if [ ! -e "$scene/scene.json" ]; then
    start=$SECONDS
    "$bin/ccdbench-${VARIANTS##* }" --threads "$threads" generate spinning-ball --resolution 708 --frames 10 --first-frame 6 \
      --out "$scene" > "$out/generate-large.txt"
    echo "generated in $((SECONDS - start)) s"
  fi
  for v in $VARIANTS; do run "$v" large --scene "$scene" --repeat "$LARGE_REPEATS"; done
  pack
fi
