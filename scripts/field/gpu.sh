#!/usr/bin/env bash
# The field on the GPU (reports/field/README.md, "On the GPU: Scalable CCD"): Scalable CCD's whole step, through its plugin
# (examples/plugins/scalable_ccd/, built by `scripts/field/build.sh scalable_ccd` on a machine with nvcc), beside
# ccdbench's own OpenCL `full` with its conservative and cubic64 narrow phases, on the same GPU, in one ccdbench
# invocation per source of steps: every step verified against the exact truth, TOIs checked, 3 passes (answers that
# change between passes are the cell's verdict). While each invocation runs, nvidia-smi samples every 100 ms how much
# device memory each process holds: ccdbench's own (its OpenCL cells) and the plugin's child (Scalable CCD's).
# Runs on the GPU machine and builds nothing: scripts/device-carry.sh, with the plugin and libcudart copied beside it
# (reports/field/README.md, "On the GPU", says how). Writes OUT_DIR/STAGE.{json,results.jsonl,txt,log,smi,pid,command}
# and gpu.txt, version.txt; then `scripts/field/field.py gpu OUT_DIR...` condenses them into reports/field/data/gpu.csv
# and gpu.json, and `field.py tables` writes the table.
# Usage: scripts/field/gpu.sh OUT_DIR PLUGIN [STAGE...]
#   STAGE: cloth-funnel rod-twist default large (default: all; each resumes nothing, so stages can run in separate
#          calls with one OUT_DIR)
# Environment: CCDBENCH_DATA_DIR the public data (default: device-carry/data, else scripts/data-dir.sh's).
set -euo pipefail
out=${1:?usage: gpu.sh OUT_DIR PLUGIN [STAGE...]}
plugin=$(cd "$(dirname "${2:?usage: gpu.sh OUT_DIR PLUGIN [STAGE...]}")" && pwd)/$(basename "$2")
shift 2
stages=("$@")
[ ${#stages[@]} -gt 0 ] || stages=(cloth-funnel rod-twist default large)
root=$(cd "$(dirname "$0")/../.." && pwd)
source "$root/scripts/device-ccdbench.sh"
[ -n "${CCDBENCH_DATA_DIR:-}" ] || [ ! -d "$root/device-carry/data" ] || export CCDBENCH_DATA_DIR=$root/device-carry/data
[ -n "${CCDBENCH_DATA_DIR:-}" ] || source "$root/scripts/data-dir.sh"
data=${CCDBENCH_DATA_DIR:?"gpu: no public data (CCDBENCH_DATA_DIR)"}
nvidia_opencl
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-/tmp/ccdbench-field-gpu-cache}
mkdir -p "$out"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader > "$out/gpu.txt"
"$bin" --version --verbose > "$out/version.txt"
"$bin" devices >> "$out/version.txt" 2>&1 || true
# Seconds a step of the plugin may take (its call's error past it): the large suite's steps hold about 3e8
# candidate pairs; ccdbench's own OpenCL step takes about 0.4 s there on an H200.
step_timeout=120
# Both forms of every cell's answers are judged: the plugin claims never to miss, so a miss or a late TOI is a
# finding; 3 passes so that answers that change between calls (the outside audit's cause) are seen.
strategies="full:backend=opencl,full+cubic64:backend=opencl,plugin:$plugin:timeout=$step_timeout"
funnel=$data/scalable-ccd-sample/cloth-funnel/frames
rod=$data/scalable-ccd-sample/rod-twist/frames

stage() {  # stage NAME RUN_ARGUMENTS...: one invocation, its device memory sampled per process
  local name=$1
  shift
  echo "gpu: $name ($(date +%T))" >&2
  nvidia-smi --query-compute-apps=pid,used_memory --format=csv,noheader,nounits -lms 100 > "$out/$name.smi" &
  local sampler=$!
  local start
  start=$(date +%s%N)
  local command=("$bin" --threads "$(nproc)" run "$@" --toi --repeat 3 --strategy "$strategies" --json "$out/$name.json"
    --out "/tmp/field-gpu-runs/$name" --fresh)
  printf '%q ' "${command[@]}" > "$out/$name.command"
  "${command[@]}" > "$out/$name.txt" 2> "$out/$name.log" &
  local running=$!
  echo "$running" > "$out/$name.pid"
  local status=0
  wait "$running" || status=$?
  echo "$(( ($(date +%s%N) - start) / 1000000 ))" > "$out/$name.wall_ms"
  kill "$sampler" 2> /dev/null || true
  wait "$sampler" 2> /dev/null || true
  # Every cell finished, as --out keeps it: what a stage cut short (a time limit) still gives.
  cp "/tmp/field-gpu-runs/$name/results.jsonl" "$out/$name.results.jsonl" 2> /dev/null || true
  echo "gpu: $name: exit $status, $(cat "$out/$name.wall_ms") ms" >&2
  tail -n 3 "$out/$name.log" >&2
}

for s in "${stages[@]}"; do
  case $s in
    cloth-funnel) stage cloth-funnel --frames "$funnel/227.ply" "$funnel/228.ply" --thickness 0 ;;
    rod-twist) stage rod-twist --frames "$rod/3036.ply" "$rod/3037.ply" --thickness 0 ;;
    default) stage default --suite default --thickness scene,0 ;;
    large) stage large --suite large --thickness scene,0 ;;
    *) echo "gpu: $s: not a stage (cloth-funnel rod-twist default large)" >&2; exit 2 ;;
  esac
done
