#!/usr/bin/env bash
# Thread scaling of full and apccd on a many-core machine (the device), building nothing there: it runs the
# binary carried in device-carry/ (bin/ccdbench and the shared libraries `ldd` lists, without libc and libm).
# Usage, on the device: scripts/device-threads.sh OUT_DIR [THREADS...]
set -euo pipefail
out=${1:?usage: device-threads.sh OUT_DIR [THREADS...]}
shift
threads=("${@:-1 2 4 8 12 16}")
root=$(cd "$(dirname "$0")/.." && pwd)
export LD_LIBRARY_PATH="$root/device-carry/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-/tmp/ccdbench-cache}
bin="$root/device-carry/bin/ccdbench"
mkdir -p "$out"
echo "machine: $(nproc) cores, $(uname -m)"
for scene in spinning-ball drape; do
  printf '{"generator": {"name": "%s", "resolution": %d, "frames": %d}}\n' "$scene" "${RESOLUTION:-100}" "${FRAMES:-60}" > "$out/$scene.json"
  for t in ${threads[@]}; do
    "$bin" --threads "$t" run --scene "$out/$scene.json" --strategy full,apccd --verify none --repeat 1 --fresh \
      --out "/tmp/threads-$scene-$t" --json "$out/$scene-t$t.json" 2>/dev/null |
      awk -v t="$t" -v s="$scene" 'NR > 1 && $4 ~ /^(full|apccd)/ {split($4, n, ":"); printf "%-14s threads %-3s %-20s %s ms/step\n", s, t, n[1], $5}'
  done
done
