#!/usr/bin/env bash
# Probe (issue 66): bd93a8d against 5ba95fb (the hand-out-first coordinator, the deferred digests), release builds
# without the trace: the 36-cell sweep with 1 and 2 ranks on one GPU, alternated, two rounds.
set -uo pipefail
mkdir -p device-carry && tar -xJf carry.tar.xz -C device-carry
export STRATEGY=full:backend=opencl,full+cubic64:backend=opencl,apccd:backend=opencl THICKNESS=scene,0 RANKS="1 2"
for run in base-1 new-1 base-2 new-2; do
  cp device-carry/bin/ccdbench-${run%-*} device-carry/bin/ccdbench
  timeout -k 5 150 scripts/device-gpus.sh "$OUT/$run" > "$OUT/$run.out" 2>&1
  pkill -f 'nvidia-smi --query-gpu' || true
  echo "-- $run"; grep -v pmix "$OUT/$run.out" | grep -E "^([12] |r[12]-|answers|  )"
done
cd "$OUT" && tar -czf s.tgz */ && rm -rf */
