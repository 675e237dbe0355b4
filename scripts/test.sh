#!/usr/bin/env bash
# Builds ccdbench and runs every test, then the `ci` suite and the CI gate on missed collisions.
# Usage: scripts/test.sh [release|debug|asan] (default: release).
# The tests that need the public data (docs/DATA.md) skip without it; after ctest, the skipped tests are listed once,
# grouped by the reason each gave. Set CCDBENCH_REQUIRE_DATA=1 to fail them instead (CI does).
set -euo pipefail
cd "$(dirname "$0")/.."
preset=${1:-release}
scripts/build.sh "$preset"
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-$PWD/build/cache}
source scripts/data-dir.sh
echo "test.sh: public data: ${CCDBENCH_DATA_DIR:-none (its tests skip; scripts/fetch-data.sh gets it)}"
# A test that hangs fails after 10 minutes (the longest takes about 1.5 under ASan on 2 cores) instead of holding CI.
# ctest's own list of the tests that did not run is left out: ctest-skips.sh lists them with their reasons.
status=0
ctest --preset "$preset" -j "$(nproc)" --timeout 600 | sed '/^The following tests did not run:/,/^$/d' || status=$?
scripts/ctest-skips.sh "build/$preset"
[ "$status" -eq 0 ] || exit "$status"
# The Python module's tests (python/tests, pytest's summary below), where the module was built (not under the
# sanitizers: an uninstrumented python3 cannot load it). Debian's python3, which has numpy and pytest.
if [ -f "build/$preset/python/ccdbench/__init__.py" ]; then
  PYTHONPATH=$PWD/build/$preset/python /usr/bin/python3 -m pytest -p no:cacheprovider -q python/tests
elif [ "$preset" = release ]; then
  echo "test.sh: the Python module was not built (pybind11-dev or python3-dev missing: scripts/setup.sh installs them)" >&2
  exit 1
fi
out=build/$preset/ci-results
# The gate: full and apccd (conservative) and full+cubic64 at the scenes' δ and at δ = 0, every step verified, TOIs too. Every
# gated cell has colliding pairs (check fails a cell that has none), and every cell needs its baseline entry.
"build/$preset/bin/ccdbench" run --suite ci --toi --strategy full,full+cubic64,apccd --out "$out" --json "$out/summary.json" --fresh
"build/$preset/bin/ccdbench" run --suite ci --toi --thickness 0 --strategy full,full+cubic64,apccd --out "$out-0" --json "$out-0/summary.json" --fresh
"build/$preset/bin/ccdbench" check --baseline tests/baselines/ci.json "$out/summary.json" "$out-0/summary.json"
# Every command block of the README and of docs/, as written, and the output each page claims (docs/development.md,
# "The docs walkthrough"; with the Release build, which the audit page installs).
if [ "$preset" = release ]; then /usr/bin/python3 scripts/docs-walkthrough.py; fi
