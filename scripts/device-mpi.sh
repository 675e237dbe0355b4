#!/usr/bin/env bash
# MPI scaling on one many-core machine (reports/mpi/): the exact truth of two paper scenes × STEPS steps, and a
# verified knob sweep of apccd on them, each with RANKS × THREADS = every core, from a cold truth cache for each
# row (the scenes' frames are generated once, before the first row). Builds nothing: on a machine without
# OpenMPI it runs what scripts/device-carry.sh put in device-carry/, else the release build and the system's mpirun.
# Usage: scripts/device-mpi.sh OUT_DIR   (STEPS=20, RESOLUTION=100, CORES=$(nproc), RANKS="1 2 4 8 16",
#        PARTS="truth sweep": which columns to measure; a part not measured shows "-")
set -euo pipefail
out=${1:?usage: device-mpi.sh OUT_DIR}
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/scripts/device-ccdbench.sh"
steps=${STEPS:-20}
resolution=${RESOLUTION:-100}
cores=${CORES:-$(nproc)}
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-/tmp/ccdbench-mpi-cache}
mkdir -p "$out"
scenes=()
for scene in spinning-ball drape; do
  printf '{"generator": {"name": "%s", "resolution": %d, "frames": %d}}\n' "$scene" "$resolution" "$((steps + 1))" > "$out/$scene.json"
  scenes+=("$out/$scene.json")
done
sweep=full,apccd:nf_max=2,apccd:nf_max=4,apccd,apccd:nf_max=16,apccd:skip=off,apccd:heuristic=off,apccd:inflation_max=0.25
"$bin" --threads "$cores" run --scene "${scenes[@]}" --strategy full --verify none --max-steps 1 --fresh --out /tmp/mpi-warm > /dev/null 2>&1
echo "machine: $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')); $("$bin" --version)"
echo "scenes: spinning-ball and drape, resolution $resolution, $steps steps each; sweep: $sweep"
printf '%-6s %-8s %-10s %-12s\n' ranks threads truth sweep
for ranks in ${RANKS:-1 2 4 8 16}; do
  threads=$((cores / ranks))
  launch=(mpirun -n "$ranks" --oversubscribe --bind-to none "$bin" --threads "$threads")
  truth=- sweep_ms=-
  if [[ " ${PARTS:-truth sweep} " == *" truth "* ]]; then
    rm -rf "$CCDBENCH_CACHE_DIR/truth"
    start=$(date +%s%N)
    for scene in "${scenes[@]}"; do
      name=$(basename "$scene" .json)
      "${launch[@]}" truth --scene "$scene" --steps "$steps" --json "$out/truth-$name-r$ranks-t$threads.json" \
        > "$out/truth-$name-r$ranks-t$threads.txt" 2> /dev/null
    done
    truth="$((($(date +%s%N) - start) / 1000000)) ms"
  fi
  if [[ " ${PARTS:-truth sweep} " == *" sweep "* ]]; then
    rm -rf "$CCDBENCH_CACHE_DIR/truth"
    start=$(date +%s%N)
    "${launch[@]}" run --scene "${scenes[@]}" --max-steps "$steps" --strategy "$sweep" --fresh --out "/tmp/mpi-sweep-r$ranks-t$threads" \
      --json "$out/sweep-r$ranks-t$threads.json" > "$out/sweep-r$ranks-t$threads.txt" 2> "$out/sweep-r$ranks-t$threads.log"
    sweep_ms="$((($(date +%s%N) - start) / 1000000)) ms"
  fi
  printf '%-6s %-8s %-10s %-12s\n' "$ranks" "$threads" "$truth" "$sweep_ms"
done
