#!/usr/bin/env bash
# How often compare's time verdict is right on this machine (docs/ci-regression.md, "Time verdicts"), counted as a
# maintainer meets it:
#   identical  COUNT comparisons of the same code: how many `compare --fail-on-slower` passes (exit 0);
#   slowdown   COUNT comparisons whose head is the template plugin made 1.25x slower on purpose, each query and each
#              whole step (tests/plugins/slowed_ccd.cpp, the same file name as the template's, as a rebuild is):
#              how many it flags;
# on the ci suite (the template in-process; the scene with analytic shapes is left out for the plugin, which refuses
# it; apart also full and apccd) and on the kinematic fold at resolution 16, at the scenes' δ and at 0. Every run has
# REPEAT timed passes (--verify none: times are what is judged). Each count is taken two ways:
#   paired  base and head in one run with their passes in turn (run --interleave, the plugin twice from two folders),
#           `compare RUN RUN --pair BASE HEAD --fail-on-slower`: what a CCD's own CI does (examples/ci/regression.sh).
#           Flagged: compare exits 1 and calls every cell of the pair slower;
#   apart   base and head in two runs, one after the other (two results folders, as of two builds of ccdbench).
#           compare gates no time of runs apart; counted is what its table calls them: identical code "called
#           slower" when any cell is, the slowdown flagged when every cell of the plugin is.
# Prints one line per set and way, the slowed plugin's head/base ratios (paired), and each comparison's rows to a
# log.
# Usage: scripts/time-verdicts.sh [COUNT] [REPEAT] [NOISE_BAND]   (after scripts/build.sh; 20, 15 and compare's default)
set -euo pipefail
cd "$(dirname "$0")/.."
count=${1:-20}
repeat=${2:-15}
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

declare -A paired=([ci]="--suite ci --thickness scene,0" [fold16]="--scene $work/fold16 --thickness scene,0")
base_plugin=plugin:$work/base/libmy.so:isolate=off
head_plugin=plugin:$work/head/libmy.so:isolate=off
mkdir -p "$work/base" "$work/head"

run_paired() {  # SET OUT: the base and head plugins' cells in one run
  rm -rf "${work:?}/$2"
  # shellcheck disable=SC2086  # the set's arguments are a list
  "$R/bin/ccdbench" run ${paired[$1]} --strategy "$base_plugin,$head_plugin" --repeat "$repeat" --interleave --verify none --fresh --out "$work/$2" > /dev/null 2>&1
}

# A comparison's table rows of the plugin's cells: they hold "→" and the ratio ("1.23x"); the notes under the table
# name the cells too, paired ones with "→", but hold no ratio.
plugin_rows() { grep -E '^[^ ].*libmy\.so.*→.* [0-9.]+x ' "$1" || true; }

# Whether every row of the plugin's cells in a comparison says slower beyond the noise.
all_plugin_rows_slower() {
  local rows slower
  rows=$(plugin_rows "$1" | grep -c . || true)
  slower=$(plugin_rows "$1" | grep -c 'slower beyond noise' || true)
  ((rows > 0 && slower == rows))
}

# Whether any table row of a comparison says slower beyond the noise (gated or not).
any_row_slower() { grep -E '^[^ ].*→.* [0-9.]+x ' "$1" | grep -q 'slower beyond noise'; }

# The head/base ratios of the plugin's rows, appended to a list.
ratios_of() { plugin_rows "$1" | grep -oE ' [0-9.]+x ' | tr -d 'x ' >> "$2" || true; }

compare() {  # OUT BASE HEAD [--pair ...]: compare --fail-on-slower into OUT; exit status as compare's
  local out=$1
  shift
  # shellcheck disable=SC2086  # an empty band is no argument
  "$R/bin/ccdbench" compare "$@" --fail-on-slower $band --replay "$work/replay" > "$out" 2>&1
}

# Appends a comparison's table rows to the log under LABEL.
log_rows() {  # LABEL FILE
  { echo "$1"; grep ' / ' "$2" | grep -v '^  ' || true; } >> "$log"
}

for set in ci fold16; do
  quiet=0 called=0 flagged=0 quiet_paired=0 flagged_paired=0
  : > "$work/ratios"
  for ((k = 0; k < count; ++k)); do
    # Paired: one run, passes in turn.
    cp "$R/plugins/libmy_ccd.so" "$work/base/libmy.so"
    cp "$R/plugins/libmy_ccd.so" "$work/head/libmy.so"
    run_paired "$set" pair
    if compare "$work/identical.txt" "$work/pair" "$work/pair" --pair "$base_plugin" "$head_plugin"; then quiet_paired=$((quiet_paired + 1)); fi
    log_rows "identical paired $set $k" "$work/identical.txt"
    cp "$R/plugins/libslowed_ccd.so" "$work/head/libmy.so"
    run_paired "$set" pair
    status=0
    compare "$work/slowdown.txt" "$work/pair" "$work/pair" --pair "$base_plugin" "$head_plugin" || status=$?
    if ((status == 1)) && all_plugin_rows_slower "$work/slowdown.txt"; then flagged_paired=$((flagged_paired + 1)); fi
    ratios_of "$work/slowdown.txt" "$work/ratios"
    log_rows "slowdown paired $set $k" "$work/slowdown.txt"
    # Apart: two runs.
    cp "$R/plugins/libmy_ccd.so" "$work/libmy.so"
    run "$set" base
    run "$set" head
    if compare "$work/identical.txt" "$work/base" "$work/head"; then quiet=$((quiet + 1)); fi
    if any_row_slower "$work/identical.txt"; then called=$((called + 1)); fi
    log_rows "identical apart $set $k" "$work/identical.txt"
    cp "$R/plugins/libmy_ccd.so" "$work/libmy.so"
    run "$set" base
    cp "$R/plugins/libslowed_ccd.so" "$work/libmy.so"
    run "$set" head
    compare "$work/slowdown.txt" "$work/base" "$work/head" || true
    if all_plugin_rows_slower "$work/slowdown.txt"; then flagged=$((flagged + 1)); fi
    log_rows "slowdown apart $set $k" "$work/slowdown.txt"
  done
  ratios=$(sort -n "$work/ratios" | awk '{a[NR] = $1} END {if (NR) printf "%s to %s, median %s", a[1], a[NR], a[int((NR + 1) / 2)]}')
  echo "time-verdicts: $set: paired (one run, --interleave): compare --fail-on-slower exited 0 in $quiet_paired of $count identical comparisons; the 1.25x slowdown flagged in $flagged_paired of $count (--repeat $repeat${3:+, --noise-band $3}; its cells' head/base: $ratios)"
  echo "time-verdicts: $set: apart (two runs): compare --fail-on-slower exited 0 in $quiet of $count identical comparisons (times of runs apart are not gated); its table called a cell slower in $called of $count, and every cell of the 1.25x slowdown slower in $flagged of $count"
done
echo "time-verdicts: each comparison's rows: $log"
