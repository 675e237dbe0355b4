#!/usr/bin/env bash
# Builds ccdbench and runs every test, then the `ci` suite and the CI gate on missed collisions.
# Usage: scripts/test.sh [release|debug|asan] (default: release).
# Set CCDBENCH_REQUIRE_DATA=1 to fail (not skip) the tests that need the public data (CI does).
set -euo pipefail
cd "$(dirname "$0")/.."
preset=${1:-release}
scripts/build.sh "$preset"
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-$PWD/build/cache}
# A test that hangs fails after 10 minutes (the longest takes about 1.5 under ASan on 2 cores) instead of holding CI.
ctest --preset "$preset" -j "$(nproc)" --timeout 600
out=build/$preset/ci-results
# The gate: full and apccd (conservative) and full+cubic64 at the scenes' δ and at δ = 0, every step verified, TOIs too. Every
# gated cell has colliding pairs (check fails a cell that has none), and every cell needs its baseline entry.
"build/$preset/bin/ccdbench" run --suite ci --toi --strategy full,full+cubic64,apccd --out "$out" --json "$out/summary.json" --fresh
"build/$preset/bin/ccdbench" run --suite ci --toi --thickness 0 --strategy full,full+cubic64,apccd --out "$out-0" --json "$out-0/summary.json" --fresh
"build/$preset/bin/ccdbench" check --baseline tests/baselines/ci.json "$out/summary.json" "$out-0/summary.json"
