#!/usr/bin/env bash
# The main job: builds ccdbench (Release) and runs the default suite (seven built-in scenes at small resolution, each
# colliding at its own δ and at δ = 0) with every strategy family: full and apccd with the conservative and the
# cubic64 narrow phase at both δ, FCL (fcl, fcl-bvh) at δ = 0, and the OpenCL backend (full, apccd) where an OpenCL
# device is usable (PoCL, which setup installs, gives every machine one). Every step is verified against the exact
# truth (computed once and cached). Ends with the table, the report's path and its plots.
# Extra arguments go to `ccdbench run` (e.g. --fresh, or --strategy LIST to run other strategies).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh python3-matplotlib  # for the report's plots
scripts/build.sh release
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-$PWD/build/cache}
ccdbench=build/release/bin/ccdbench

strategies=full,full+cubic64,apccd,apccd+cubic64
if "$ccdbench" --version | grep -q "FCL on"; then
  strategies+=,fcl,fcl-bvh
else
  echo "run.sh: FCL is not in this build (CCDBENCH_WITH_FCL=OFF): fcl and fcl-bvh are not shown"
fi
# One JSON object per device; a usable one takes full:backend=opencl, and with 64-bit atomics apccd:backend=opencl.
devices=$("$ccdbench" devices --json 2>&1 || true)
if grep -q '"int64_atomics":true.*"usable":true' <<<"$devices"; then
  strategies+=,full:backend=opencl,apccd:backend=opencl
elif grep -q '"usable":true' <<<"$devices"; then
  strategies+=,full:backend=opencl
  echo "run.sh: the OpenCL device has no 64-bit atomics: apccd:backend=opencl is not shown"
else
  echo "run.sh: no usable OpenCL device, so the OpenCL backend is not shown (ccdbench devices says: ${devices:-no device})"
fi

report=reports/runs/$(date -u +%Y%m%d-%H%M%S)
"$ccdbench" run --suite default --thickness scene,0 --strategy "$strategies" --out results/default --report "$report" "$@"
/usr/bin/python3 scripts/plot_run.py "$report"
echo "report: $report/README.md (plots: speedup.png, verdicts.png, stages.png, ms_per_step.png)"
