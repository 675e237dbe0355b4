#!/usr/bin/env bash
# How often compare's time verdict is right on this machine (docs/ci-regression.md, "Time verdicts"), counted as a
# maintainer meets it: two runs of one command, then `compare BASE HEAD --fail-on-slower`.
#   identical  COUNT pairs of runs of the same code: how many comparisons exit 0 (nothing called slower);
#   slowdown   COUNT pairs whose head is the template plugin made 1.25x slower (tests/plugins/slowed_ccd.cpp, the
#              same file name as the template's, as a rebuild is): how many call its cells slower beyond the noise;
# on the ci suite (full, apccd and the template in-process; the scene with analytic shapes is left out for the plugin,
# which refuses it) and on the kinematic fold at resolution 16. Every run has REPEAT timed passes (--verify none: times
# are what is judged). Prints one line per count and set, and each comparison's head/base ratios to a log.
# Usage: scripts/time-verdicts.sh [COUNT] [REPEAT] [NOISE_BAND]   (after scripts/build.sh; 20, 9 and compare's default)
set -euo pipefail
cd "$(dirname "$0")/.."
count=${1:-20}
repeat=${2:-9}
band=${3:+--noise-band $3}
R=$PWD/build/release
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-$PWD/build/cache}
"$R/bin/ccdbench" generate fold --resolution 16 --out "$work/fold16" > /dev/null
log=${TIME_VERDICTS_LOG:-$work/comparisons.log}
: > "$log"
plugin=plugin:$work/libmy.so:isolate=off
declare -A sets=([ci]="--suite ci --thickness scene,0 --strategy full,apccd,$plugin" [fold16]="--scene $work/fold16 --thickness scene,0 --strategy full,$plugin")

run() {  # SET OUT (a fresh folder: a rebuilt plugin's cells must not meet the last build's)
  rm -rf "${work:?}/$2"
  # shellcheck disable=SC2086  # the set's arguments are a list
  "$R/bin/ccdbench" run ${sets[$1]} --repeat "$repeat" --verify none --fresh --out "$work/$2" > /dev/null 2>&1
}

for set in ci fold16; do
  quiet=0
  flagged=0
  for ((k = 0; k < count; ++k)); do
    cp "$R/plugins/libmy_ccd.so" "$work/libmy.so"
    run "$set" base
    run "$set" head
    # shellcheck disable=SC2086  # an empty band is no argument
    if "$R/bin/ccdbench" compare "$work/base" "$work/head" --fail-on-slower $band --replay "$work/replay" > "$work/identical.txt" 2>&1; then
      quiet=$((quiet + 1))
    fi
    { echo "identical $set $k"; grep ' / ' "$work/identical.txt" | grep -v '^  ' || true; } >> "$log"
    cp "$R/plugins/libmy_ccd.so" "$work/libmy.so"
    run "$set" base
    cp "$R/plugins/libslowed_ccd.so" "$work/libmy.so"
    run "$set" head
    # shellcheck disable=SC2086
    "$R/bin/ccdbench" compare "$work/base" "$work/head" --fail-on-slower $band --replay "$work/replay" > "$work/slowdown.txt" 2>&1 || true
    # Flagged: every cell of the slowed plugin called slower beyond the noise.
    plugin_rows=$(grep -c '^[^ ].*libmy\.so' "$work/slowdown.txt" || true)
    slower_rows=$(grep '^[^ ].*libmy\.so' "$work/slowdown.txt" | grep -c 'slower beyond noise' || true)
    if ((plugin_rows > 0 && slower_rows == plugin_rows)); then flagged=$((flagged + 1)); fi
    { echo "slowdown $set $k"; grep ' / ' "$work/slowdown.txt" | grep -v '^  ' || true; } >> "$log"
  done
  echo "time-verdicts: $set: identical runs: compare --fail-on-slower exited 0 in $quiet of $count; 1.25x slowdown flagged in $flagged of $count (--repeat $repeat${3:+, --noise-band $3})"
done
echo "time-verdicts: each comparison's rows: $log"
