#!/usr/bin/env bash
# The OpenCL report's runs on the GPU machine (reports/opencl/README.md): builds nothing, uses what
# scripts/device-carry.sh put into device-carry/ (ccdbench, opencl_tests and the libraries they need). Registers
# the machine's NVIDIA OpenCL driver (installed, not registered), then:
#   1. parity: opencl_tests' OpenClParity tests on the first GPU (ci and default suites, both public steps, and
#      the paper suite's first $PARITY_STEPS steps), every step's set and TOIs against the CPU's;
#   2. the public steps: CPU full on 1 thread, CPU full on every core, and full:backend=opencl, conservative and
#      cubic64, every step verified, median of 5 passes (1 for one thread);
#   3. the paper suite's first $PAPER_STEPS steps, the same strategies, every step verified;
#   4. the stand-in for a step with tens of millions of elementary candidates: the kinematic fold at resolution
#      $BIG_RESOLUTION with δ = $BIG_THICKNESS (several edge lengths), parity on its first step, then timings.
#   5. apccd (issue 16), each with its own parts:
#      apccd-parity: apccd:backend=opencl against the CPU apccd on the paper suite's first $APCCD_PARITY_STEPS steps
#        (0: all), both δ, conservative: every step's set, TOIs and session counters (and the ci suite's tests);
#      apccd-paper-delta, apccd-paper-zero: the paper suite (first $APCCD_PAPER_STEPS steps, 0: all) at the scenes'
#        δ and at δ = 0, full and apccd on the CPU (every core) and on the device, every step verified;
#      apccd-large: spinning-ball at resolution 317 (about 200k triangles), 20 steps: parity on its first
#        $LARGE_PARITY_STEPS steps, the first $LARGE_VERIFIED_STEPS steps verified, then all 20 with --verify none.
# PART_TIMEOUT (seconds) stops an apccd-paper run before the device's 10-minute call ends; its finished cells stay in
# $out/runs-paper-* and are packed, and the same command on the still-warm machine resumes from them.
#      attribution: the paper suite at the scenes' δ, --verify none, full, full:filter=on, apccd:skip=off and apccd
#        on the CPU (every core) and on the device.
# PARTS chooses among "parity public paper big apccd-parity apccd-paper-delta apccd-paper-zero attribution apccd-large"
# (default: the first four). Writes every table and JSON summary to a work
# folder and, when $OUT is set (the device's return folder), packs them into $OUT/opencl-device.tgz.
# Usage (from the repository root): scripts/device-opencl.sh
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/device-env.sh
out=/tmp/ccdbench-opencl
PARTS=${PARTS:-parity public paper big}
mkdir -p "$out" /tmp/icd
# Packed after every part too, so that a call cut off at its time limit still returns what finished.
pack() { if [ -n "${OUT:-}" ]; then tar czf "$OUT/opencl-device.tgz" --exclude='./runs' -C "$out" .; fi; }
trap pack EXIT
echo libnvidia-opencl.so.1 > /tmp/icd/nvidia.icd
export OCL_ICD_VENDORS=/tmp/icd
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-/tmp/ccdbench-cache}
threads=$(nproc)
bin=device-carry/bin
data=${CCDBENCH_DATA_DIR:-device-carry/data}
PARITY_STEPS=${PARITY_STEPS:-10}
PAPER_STEPS=${PAPER_STEPS:-20}
PAPER_STEPS_ONE_THREAD=${PAPER_STEPS_ONE_THREAD:-5}
BIG_RESOLUTION=${BIG_RESOLUTION:-250}
BIG_THICKNESS=${BIG_THICKNESS:-0.018}
APCCD_PARITY_STEPS=${APCCD_PARITY_STEPS:-0}
APCCD_PAPER_STEPS=${APCCD_PAPER_STEPS:-0}
LARGE_PARITY_STEPS=${LARGE_PARITY_STEPS:-5}
LARGE_VERIFIED_STEPS=${LARGE_VERIFIED_STEPS:-2}

{ nproc; lscpu | grep -E 'Model name|^CPU\(s\)'; nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader || true; } > "$out/machine.txt" 2>&1
"$bin/ccdbench" --version >> "$out/machine.txt"
"$bin/ccdbench" devices | tee "$out/devices.txt"

part() { [[ " $PARTS " == *" $1 "* ]]; }
if part parity; then
echo "== parity (opencl_tests on the first GPU)"
start=$SECONDS
CCDBENCH_DATA_DIR=$data CCDBENCH_REQUIRE_DATA=1 CCDBENCH_PARITY_SUITE=paper CCDBENCH_PARITY_STEPS=$PARITY_STEPS \
  "$bin/opencl_tests" --gtest_filter='OpenClParity.*' 2>&1 | tee "$out/parity.txt" | grep -E '^\[ +(OK|FAILED|PASSED) ' || true
echo "parity: $((SECONDS - start)) s" | tee -a "$out/parity.txt"
fi

frames() { echo "$data/scalable-ccd-sample/$1/frames/$2.ply $data/scalable-ccd-sample/$1/frames/$3.ply"; }
gpu="full:backend=opencl,full+cubic64:backend=opencl"
if part public; then
for step in "rod-twist 3036 3037" "cloth-funnel 227 228"; do
  set -- $step
  echo "== $1 $2 -> $3"
  "$bin/ccdbench" --threads 1 run --frames $(frames "$1" "$2" "$3") --strategy full,full+cubic64 \
    --out "$out/runs" --json "$out/$1-1thread.json" 2>/dev/null | tee "$out/$1-1thread.txt"
  "$bin/ccdbench" --threads "$threads" run --frames $(frames "$1" "$2" "$3") --repeat 5 --strategy "full,full+cubic64,$gpu" \
    --out "$out/runs" --json "$out/$1-${threads}threads.json" 2>/dev/null | tee "$out/$1-${threads}threads.txt"
done
fi

if part paper; then
echo "== paper suite, first $PAPER_STEPS steps"
"$bin/ccdbench" --threads 1 run --suite paper --max-steps "$PAPER_STEPS_ONE_THREAD" --strategy full \
  --out "$out/runs" --json "$out/paper-1thread.json" 2>/dev/null | tee "$out/paper-1thread.txt"
"$bin/ccdbench" --threads "$threads" run --suite paper --max-steps "$PAPER_STEPS" --strategy "full,full+cubic64,$gpu" \
  --out "$out/runs" --json "$out/paper-${threads}threads.json" 2>/dev/null | tee "$out/paper-${threads}threads.txt"
fi

if part big; then
echo "== fold r$BIG_RESOLUTION, δ = $BIG_THICKNESS"
"$bin/ccdbench" generate fold --resolution "$BIG_RESOLUTION" --frames 4 --out /tmp/ccdbench-fold > /dev/null
CCDBENCH_PARITY_SCENE=/tmp/ccdbench-fold/scene.json CCDBENCH_PARITY_THICKNESS=$BIG_THICKNESS CCDBENCH_PARITY_STEPS=1 \
  "$bin/opencl_tests" --gtest_filter='*TheSceneAskedFor*' 2>&1 | tee "$out/big-parity.txt" | grep -E '^\[ +(OK|FAILED|counts) ' || true
"$bin/ccdbench" --threads "$threads" run --scene /tmp/ccdbench-fold --thickness "$BIG_THICKNESS" --max-steps 3 --verify none \
  --strategy "full,full+cubic64,$gpu" --out "$out/runs" --json "$out/big-${threads}threads.json" 2>/dev/null | tee "$out/big-${threads}threads.txt"
fi
apccd_cells="full,apccd,full:backend=opencl,apccd:backend=opencl"
# The attribution of apccd's gain (issue 17): full, full with apccd's separation filter, apccd without and with
# skipping, on the CPU and on the device; --verify none (the verified runs above hold the 0 missed).
attribution_cells="full,full:filter=on,apccd:skip=off,apccd,full:backend=opencl,full:filter=on:backend=opencl,apccd:skip=off:backend=opencl,apccd:backend=opencl"
if part apccd-parity; then
echo "== apccd parity (opencl_tests on the first GPU)"
start=$SECONDS
CCDBENCH_PARITY_SUITE=paper CCDBENCH_PARITY_STEPS=$APCCD_PARITY_STEPS CCDBENCH_PARITY_STRATEGY=apccd CCDBENCH_PARITY_NARROW=conservative \
  "$bin/opencl_tests" --gtest_filter='OpenClParity.Apccd*:OpenClParity.TheSuiteAskedFor*' 2>&1 | tee "$out/apccd-parity.txt" \
  | grep -E '^\[ +(OK|FAILED|PASSED|counts) ' || true
echo "apccd parity: $((SECONDS - start)) s" | tee -a "$out/apccd-parity.txt"
pack
fi
for delta in delta zero; do
  part "apccd-paper-$delta" || continue
  echo "== apccd, paper suite ($delta), first $APCCD_PAPER_STEPS steps (0: all)"
  thickness=(); [ "$delta" = zero ] && thickness=(--thickness 0)
  start=$SECONDS
  timeout "${PART_TIMEOUT:-100000}" "$bin/ccdbench" --threads "$threads" run --suite paper --max-steps "$APCCD_PAPER_STEPS" "${thickness[@]}" --strategy "$apccd_cells" \
    --out "$out/runs-paper-$delta" --json "$out/apccd-paper-$delta.json" 2>/dev/null | tee "$out/apccd-paper-$delta.txt"
  cp "$out/runs-paper-$delta/results.jsonl" "$out/apccd-paper-$delta.jsonl" || true
  echo "apccd paper $delta: $((SECONDS - start)) s" | tee -a "$out/apccd-paper-$delta.txt"
  pack
done
if part attribution; then
echo "== attribution, paper suite, first $APCCD_PAPER_STEPS steps (0: all), --verify none"
start=$SECONDS
timeout "${PART_TIMEOUT:-100000}" "$bin/ccdbench" --threads "$threads" run --suite paper --max-steps "$APCCD_PAPER_STEPS" --verify none \
  --strategy "$attribution_cells" --out "$out/runs-attribution" --json "$out/attribution.json" 2>/dev/null | tee "$out/attribution.txt" | cut -c1-150
echo "attribution: $((SECONDS - start)) s" | tee -a "$out/attribution.txt"
pack
fi
if part apccd-large; then
echo "== apccd, spinning-ball r317 (about 200k triangles), 20 steps"
start=$SECONDS
"$bin/ccdbench" generate spinning-ball --resolution 317 --frames 21 --out /tmp/ccdbench-large > /dev/null
CCDBENCH_PARITY_SCENE=/tmp/ccdbench-large/scene.json CCDBENCH_PARITY_STEPS=$LARGE_PARITY_STEPS CCDBENCH_PARITY_STRATEGY=apccd \
  CCDBENCH_PARITY_NARROW=conservative "$bin/opencl_tests" --gtest_filter='*TheSceneAskedFor*' 2>&1 | tee "$out/apccd-large-parity.txt" \
  | grep -E '^\[ +(OK|FAILED|counts) ' || true
"$bin/ccdbench" --threads "$threads" run --scene /tmp/ccdbench-large --max-steps "$LARGE_VERIFIED_STEPS" --strategy "$apccd_cells" \
  --out "$out/runs-large-verified" --json "$out/apccd-large-verified.json" 2>/dev/null | tee "$out/apccd-large-verified.txt"
"$bin/ccdbench" --threads "$threads" run --scene /tmp/ccdbench-large --verify none --strategy "$apccd_cells" \
  --out "$out/runs-large" --json "$out/apccd-large.json" 2>/dev/null | tee "$out/apccd-large.txt"
cp "$out/runs-large/results.jsonl" "$out/apccd-large.jsonl"
echo "apccd large: $((SECONDS - start)) s" | tee -a "$out/apccd-large.txt"
pack
fi
echo "done: $out"
