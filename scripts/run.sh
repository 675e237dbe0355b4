#!/usr/bin/env bash
# The main job: builds ccdbench (Release) and runs the default suite: built-in scenes at small resolution, every
# step verified against the exact truth (computed once and cached). Ends with the table and the report's path.
# Extra arguments go to `ccdbench run` (e.g. --strategy full,full+cubic64 or --fresh).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh release
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-$PWD/build/cache}
report=reports/runs/$(date -u +%Y%m%d-%H%M%S)
build/release/bin/ccdbench run --suite default --strategy full,full+cubic64 --out results/default --report "$report" "$@"
/usr/bin/python3 scripts/plot_run.py "$report"
echo "report: $report/README.md"
