#!/usr/bin/env bash
# Writes tests/ctest_costs_PRESET.cmake from the times ctest recorded in build/PRESET (run the tests of a clean clone
# first, as CI does): ctest starts the longest tests first when it has no timings of its own, so that on CI's two
# cores no long test starts last and runs alone. Only the order of tests depends on the file.
# Usage: scripts/ctest-costs.sh release|asan
set -euo pipefail
cd "$(dirname "$0")/.."
preset=${1:?usage: scripts/ctest-costs.sh release|asan}
data=build/$preset/Testing/Temporary/CTestCostData.txt
[[ -f $data ]] || { echo "ctest-costs.sh: $data: no test times (run ctest --preset $preset first)" >&2; exit 2; }
out=tests/ctest_costs_$preset.cmake
{
  echo "# ctest starts the longest tests first when it has no timings of its own (a clean clone, as in CI): the seconds each"
  echo "# took (ctest's running average in build/$preset, 2 cores, at $(git rev-parse --short HEAD)), those of a second or more."
  echo "# Only the order of tests depends on them; a name no longer in the suite is ignored. Written by scripts/ctest-costs.sh."
  # CTestCostData.txt: "NAME RUNS SECONDS" per test ever run in this build folder, then a line "---" and the failed
  # tests; only the tests the suite has now are kept.
  ctest --test-dir "build/$preset" -N | sed -n 's/^ *Test *#[0-9]*: //p' | sort -u > "$out.names"
  awk 'FNR == NR { current[$1] = 1; next } $0 == "---" { exit } NF == 3 && ($1 in current) && $3 >= 1.0 { printf "%s %d\n", $1, $3 + 0.5 }' \
      "$out.names" "$data" | sort -u | sort -k2,2nr -k1,1 | awk '{ printf "set_tests_properties(%s PROPERTIES COST %d)\n", $1, $2 }'
} > "$out.tmp"
rm "$out.names"
mv "$out.tmp" "$out"
echo "ctest-costs.sh: wrote $out ($(grep -c set_tests_properties "$out") tests)"
