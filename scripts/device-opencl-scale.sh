#!/usr/bin/env bash
# Any step on one GPU (issue 50, reports/opencl/scale/): the OpenCL step under a device memory budget (memory=), on
# the GPU machine, from what `CARRY_VARIANTS="before=PATH after=PATH" scripts/device-carry.sh` put into
# device-carry/ (builds nothing). Registers the machine's NVIDIA OpenCL driver. Every GPU run is its own process,
# sampled by nvidia-smi every $SAMPLE_MS ms (the driver's peak for that process), --verify none, and keeps each
# step's answers digest. Parts (PARTS, default "context fits scale"):
#   context: the ci suite's first 2 steps under the default budget: the driver's memory for a context and its
#            kernels, which no buffer of ours accounts for (what a peak may pass its budget by);
#   fits:    where a whole step fits, each of $VARIANTS (default "before after": the whole-step path, then the
#            chunked one; a variant between them attributes a change) on the same warm machine, $REPEATS passes:
#            the public steps rod-twist 3036 -> 3037 and cloth-funnel 227 -> 228, and steps 2-15 of the spinning
#            ball at resolution 708 (about 1M triangles; table.py picks 2, 10 and 14);
#   limits:  steps 2-15 of the same ball at the scene's δ, conservative with the first device pass giving a query
#            up after $LIMITS iterations (device_iterations=, the answers the same under any: only where the time
#            goes changes), beside cubic64; the last variant, $REPEATS passes;
#   cpu:     resting contact on the CPU (issue 51), each of $VARIANTS, `full` and `full+cubic64` in one process,
#            $REPEATS passes, all cores: steps 10 and 14 of the same ball (frames 10-11 and 14-15, each its own
#            scene) and the paper's spinning ball whole (resolution 100, 99 steps);
#   stages:  the conservative test's cost by stage against cubic64's, pair by pair on one thread, for each
#            conservative_stages build carried (CARRY_STAGES): the paper's spinning ball, steps 20-99 every 10 (the
#            CPU's narrow phase there is nearly all stage 1; a stage costing more on this CPU than elsewhere shows);
#   scale:   frames 26-28 of the same scene (2 steps past the old 2^32 ceiling: about 3e8 candidate pairs a step)
#            under memory=2G, 4G and 8G, conservative and cubic64, at δ = 0 and the scene's δ, and the CPU `full` of
#            the same steps (the answers every budget must give).
# Resumes: a run whose JSON is in the work folder is not run again, so calls that stop at the device's command
# limit continue each other on a warm machine. With $OUT set (the device's return folder) the work folder, less its
# scenes and run folders, is packed into $OUT/opencl-scale.tgz after every run. Last it prints the table
# (reports/opencl/scale/table.py FOLDER, where the machine has a python3; else run it on the folder here) and exits
# with its status: non-zero on a digest that differs from the CPU's, a failed run, or a peak above budget + context.
# Usage (repository root, GPU machine): PARTS="context scale" scripts/device-opencl-scale.sh
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/device-env.sh
out=/tmp/ccdbench-opencl-scale
source scripts/device-builds.sh
pack() { if [ -n "${OUT:-}" ]; then tar czf "$OUT/opencl-scale.tgz" -C "$out" --exclude='./scene-*' --exclude='./runs-*' .; fi; }
trap pack EXIT
PARTS=${PARTS:-context fits scale}
REPEATS=${REPEATS:-3}
VARIANTS=${VARIANTS:-before after}
SAMPLE_MS=${SAMPLE_MS:-20}
BUDGETS=${BUDGETS:-2G 4G 8G}
LIMITS=${LIMITS:-25 50 100 200 400 1000}
write_machine $VARIANTS

# keep NAME START NOTE: a finished run kept (its step records compressed, its JSON in place: done), said and packed.
keep() {
  local stem="$out/$1"
  gzip -c "$out/runs-$1/results.jsonl" > "$stem.jsonl.gz"
  rm -rf "$out/runs-$1"
  mv "$stem.json.tmp" "$stem.json"
  echo "$1: $((SECONDS - $2)) s$3"
  pack
}
# gpu NAME VARIANT STRATEGY ARGS...: one GPU run as its own process, its driver peak sampled; kept as NAME.*.
gpu() {
  local name=$1 variant=$2 strategy=$3
  shift 3
  local stem="$out/$name" start=$SECONDS
  if [ -s "$stem.json" ]; then return; fi
  "$bin/ccdbench-$variant" --threads "$threads" run "$@" --strategy "$strategy" --verify none --out "$out/runs-$name" --json "$stem.json.tmp" \
    --fresh 2> "$stem.err" > "$stem.txt" &
  local pid=$!
  nvidia-smi --query-compute-apps=pid,used_memory --format=csv,noheader,nounits -lms "$SAMPLE_MS" 2> /dev/null |
    awk -F', *' -v pid="$pid" '$1 == pid && $2 + 0 > peak {peak = $2 + 0} END {print peak + 0}' > "$stem.smi" &
  local sampler=$!
  local status=0
  wait "$pid" || status=$?
  pkill -f "nvidia-smi --query-compute-apps" 2> /dev/null || true
  wait "$sampler" 2> /dev/null || true
  if [ "$status" != 0 ]; then
    echo "$name failed ($status):"
    tail -n 3 "$stem.err"
    echo "$status" > "$stem.failed"
    return
  fi
  keep "$name" "$start" ", driver peak $(cat "$stem.smi") MiB"
}
# cpu NAME VARIANT STRATEGY ARGS...: a CPU run of the same steps (their answers; or times, in the cpu part).
cpu() {
  local name=$1 variant=$2 strategy=$3
  shift 3
  local stem="$out/$name" start=$SECONDS
  if [ -s "$stem.json" ]; then return; fi
  "$bin/ccdbench-$variant" --threads "$threads" run "$@" --strategy "$strategy" --verify none --out "$out/runs-$name" --json "$stem.json.tmp" \
    --fresh 2> "$stem.err" > "$stem.txt"
  keep "$name" "$start" ""
}
# scene NAME FRAMES FIRST: the spinning ball at resolution 708, frames FIRST..FRAMES-1, generated once.
scene() {
  local folder="$out/scene-$1"
  if [ ! -e "$folder/scene.json" ]; then
    local start=$SECONDS
    "$bin/ccdbench-after" --threads "$threads" generate spinning-ball --resolution 708 --frames "$2" --first-frame "$3" --out "$folder" \
      > "$out/generate-$1.txt"
    echo "generated $1 in $((SECONDS - start)) s" >&2
  fi
  echo "$folder"
}
# paper_ball: the paper's spinning ball (resolution 100, 100 frames), generated once.
paper_ball() {
  local paper="$out/scene-paper-ball"
  if [ ! -e "$paper/scene.json" ]; then
    "$bin/ccdbench-after" --threads "$threads" generate spinning-ball --resolution 100 --frames 100 --out "$paper" > "$out/generate-paper-ball.txt"
  fi
  echo "$paper"
}
narrow_spec() { [ "$1" = conservative ] && echo "full" || echo "full+$1"; }

if part context; then
  echo "== context: the ci suite's first 2 steps"
  gpu context after "full:backend=opencl" --suite ci --max-steps 2
fi
if part fits; then
  echo "== fits: the whole-step path (before) and the chunked path (after)"
  ball=$(scene steps-2-15 16 2)
  for narrow in conservative cubic64; do
    for v in $VARIANTS; do
      spec="$(narrow_spec $narrow):backend=opencl"
      gpu "fits-rod-twist-$narrow-$v" "$v" "$spec" --frames $(frames rod-twist 3036 3037) $(frames rod-twist 3036 3037) --repeat "$REPEATS"
      gpu "fits-cloth-funnel-$narrow-$v" "$v" "$spec" --frames $(frames cloth-funnel 227 228) $(frames cloth-funnel 227 228) --repeat "$REPEATS"
      gpu "fits-ball-$narrow-$v" "$v" "$spec" --scene "$ball" --repeat "$REPEATS"
    done
  done
fi
if part limits; then
  echo "== limits: the first device pass's iterations on the ball's steps 2-15"
  ball=$(scene steps-2-15 16 2)
  last=${VARIANTS##* }
  for limit in $LIMITS; do
    gpu "limits-$limit" "$last" "full:backend=opencl:device_iterations=$limit" --scene "$ball" --repeat "$REPEATS"
  done
  gpu "limits-cubic64" "$last" "full+cubic64:backend=opencl" --scene "$ball" --repeat "$REPEATS"
fi
if part stages; then
  echo "== stages: the conservative test by stage, one thread, the paper's spinning ball steps 20-99 every 10"
  paper=$(paper_ball)
  for stages in "$bin"/conservative_stages-*; do
    name=stages-${stages##*/conservative_stages-}
    if [ -s "$out/$name.txt" ]; then continue; fi
    "$stages" "$paper" --steps 20 99 10 > "$out/$name.txt.tmp"
    mv "$out/$name.txt.tmp" "$out/$name.txt"
    echo "${name#stages-}: $(head -n 1 "$out/$name.txt")"
    grep -E '^(stage|[0-5] )' "$out/$name.txt"
    pack
  done
fi
if part scale; then
  echo "== scale: frames 26-28 under budgets $BUDGETS"
  ball=$(scene frames-26-28 29 26)
  for thickness in 0 scene; do
    for narrow in conservative cubic64; do
      for budget in $BUDGETS; do
        gpu "scale-$thickness-$narrow-$budget" after "$(narrow_spec $narrow):backend=opencl:memory=$budget" --scene "$ball" --thickness "$thickness"
      done
    done
  done
  for thickness in 0 scene; do
    for narrow in conservative cubic64; do
      cpu "scale-$thickness-$narrow-cpu" after "$(narrow_spec $narrow)" --scene "$ball" --thickness "$thickness"
    done
  done
fi
if part cpu; then
  echo "== cpu: resting contact on the CPU, each of $VARIANTS: the ball's steps 10 and 14, the paper's spinning ball"
  for first in 10 14; do
    ball=$(scene "step-$first" $((first + 2)) "$first")
    for v in $VARIANTS; do
      cpu "cpu-step-$first-$v" "$v" "full,full+cubic64" --scene "$ball" --repeat "$REPEATS"
    done
  done
  paper=$(paper_ball)
  for v in $VARIANTS; do
    cpu "cpu-paper-ball-$v" "$v" "full,full+cubic64" --scene "$paper" --repeat "$REPEATS"
  done
fi
if command -v python3 > /dev/null; then
  python3 reports/opencl/scale/table.py "$out"
else
  echo "no python3 here: run reports/opencl/scale/table.py on the returned folder"
fi
