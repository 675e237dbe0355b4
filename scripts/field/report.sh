#!/usr/bin/env bash
# Writes reports/field/: every public CPU CCD method scripts/field/build.sh builds, side by side with ccdbench's
# conservative and cubic64 narrow phases and the exact reference, on this machine, in one command. Each table is one
# ccdbench invocation (the whole steps: one per scene source), every plugin isolated with a per-query timeout (a hang
# is an error of its query), and the whole report within the budget below (reports/field/README.md says why these
# sizes). It ends by condensing ccdbench's outputs into reports/field/data/ and writing the tables from them
# (scripts/field/field.py), so that `field.py tables --check` holds them to the data.
#
# Usage: scripts/field/report.sh
# Environment:
#   CCDBENCH_DATA_DIR       the public data (the unit tests and the two public steps; docs/DATA.md), required
#   CCDBENCH_FIELD_QUERIES  handcrafted/ and simulation/ of Sample-Queries (scripts/fetch-data.sh --field); default
#                           $CCDBENCH_DATA_DIR/field-queries, else data/external/field-queries; a set not there is
#                           left out of the tables, which say so
#   CCDBENCH_FIELD_SOURCES, CCDBENCH_FIELD_COMMIT_*, ...   for scripts/field/build.sh, which runs first
#   CCDBENCH_FIELD_WORK     build.sh's folder; samples and ccdbench's outputs go to its report/ (default build/field)
#   CCDBENCH_FIELD_METHODS  only these methods.csv keys among the plugins (comma-separated), to check one method quickly
# Exit status: that of the first step that failed; 0 when every table was written.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
data=${CCDBENCH_DATA_DIR:?"field: set CCDBENCH_DATA_DIR to the public data (docs/DATA.md; scripts/fetch-data.sh)"}
field_queries=${CCDBENCH_FIELD_QUERIES:-}
if [ -z "$field_queries" ]; then
  field_queries=$data/field-queries
  [ -d "$field_queries" ] || field_queries=$root/data/external/field-queries
fi
work=${CCDBENCH_FIELD_WORK:-$root/build/field}
plugins=${CCDBENCH_FIELD_PLUGINS:-$work/plugins}
report=$work/report
out=$report/out
ccdbench=$root/build/release/bin/ccdbench
python=/usr/bin/python3

# The budget: the whole report, on this project's 2-core machine, within an hour (measured: 48 minutes, the stages in
# the README there; the δ > 0 queries and the whole steps are the most of it).
budget_seconds=3600
# Per-query timeouts: 1 s where a method's time is measured (the slowest method's slowest answered query of the
# public sets took under 0.5 s), 0.2 s on the rescaled sets and the extremes suite, where several methods hang on
# most queries (each hang costs its timeout and about 0.4 s to start a fresh child).
timeout_timed=1
timeout_extremes=0.2
# δ > 0 for the methods with a minimum separation: 1e-3 (the sets' coordinates are of order 1; a contact at that
# distance is 1e-3 of a unit triangle).
delta=1e-3
exponents=(-1000 -500 -100 0 100 500 1000)

status=0
scripts/field/build.sh || status=$?
if [ "$status" = 1 ] || [ "$status" = 2 ]; then exit "$status"; fi
[ -x "$ccdbench" ] || { echo "field: no $ccdbench (scripts/build.sh)" >&2; exit 2; }

# The methods: every plugin methods.csv names that build.sh installed, then ccdbench's own.
specs() {  # specs TIMEOUT [DELTA_ONLY]
  local list=() key plugin delta_taken
  while IFS=, read -r key plugin delta_taken; do
    [ -n "$plugin" ] && [ -f "$plugins/$plugin" ] || continue
    if [ -n "${CCDBENCH_FIELD_METHODS:-}" ] && ! [[ ",$CCDBENCH_FIELD_METHODS," == *",$key,"* ]]; then continue; fi
    if [ "${2:-}" = delta ] && [ "${delta_taken#yes}" = "$delta_taken" ]; then continue; fi
    list+=("plugin:$plugins/$plugin:timeout=$1")
  done < <($python -c "
import csv
for m in csv.DictReader(open('reports/field/data/methods.csv')):
    print(','.join([m['key'], m['plugin'], m['delta'].replace(',', ' ')]))")
  local IFS=,
  echo "${list[*]},conservative,cubic64"
}

rm -rf "$report" && mkdir -p "$out"
step() {  # step NAME COMMAND...: runs it (its table to $out/NAME.txt), timed, and records it in $out/stages.jsonl
  local name=$1 start
  shift
  echo "field: $name" >&2
  start=$(date +%s%N)
  "$@" >"$out/$name.txt"
  $python - "$name" "$start" "$(date +%s%N)" "$root/" "$plugins/" "$report/" "$data" "$@" >>"$out/stages.jsonl" <<'EOF'
import json, shlex, sys
name, start, end, root, plugins, report, data = sys.argv[1:8]
command = shlex.join(sys.argv[8:])
for path, shown in ((plugins, "PLUGINS/"), (report, "WORK/"), (report.rstrip("/"), "WORK"), (data, "$CCDBENCH_DATA_DIR"), (root, "")):
    command = command.replace(path, shown)
print(json.dumps({"stage": name, "seconds": round((int(end) - int(start)) / 1e9, 1), "command": command}))
EOF
}

step sample $python scripts/field/field.py sample "$data" "$field_queries" "$report"
step queries "$ccdbench" --threads 1 queries "$report/queries/main" --method "$(specs $timeout_timed),exact" --toi --repeat 3 \
  --json "$out/main.json" --write-answers "$out/main.answers.csv" --faults "$out/faults-main"
step delta-labels "$ccdbench" --threads 1 queries "$report/queries/main" --method exact --thickness $delta --write-answers "$out/delta-labels.csv"
step delta-relabel $python scripts/field/field.py relabel "$out/delta-labels.csv" "$report"
step delta "$ccdbench" --threads 1 queries "$report/queries/delta" --method "$(specs $timeout_timed delta),exact" --thickness $delta --toi --repeat 3 \
  --json "$out/delta.json" --write-answers "$out/delta.answers.csv" --faults "$out/faults-delta"
for k in "${exponents[@]}"; do
  step "scale 2^$k" "$ccdbench" --threads 1 queries "$report/queries/scale" --scale-exponent "$k" --method "$(specs $timeout_extremes),exact" --toi \
    --json "$out/scale$k.json" --write-answers "$out/scale$k.answers.csv" --faults "$out/faults-scale$k"
done
step extremes "$ccdbench" --threads 1 stress --method "$(specs $timeout_extremes)" --json "$out/stress.json"
source scripts/field/steps.sh

cat >"$out/meta.json" <<EOF
{"delta": $delta, "exponents": [$(IFS=,; echo "${exponents[*]}")], "budget_seconds": $budget_seconds,
 "timeouts": {"timed": $timeout_timed, "extremes": $timeout_extremes}, "max_us_per_test": $max_us_per_test,
 "machine": "$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores", "revision": "$(git rev-parse --short HEAD)"}
EOF
cp "$plugins/MANIFEST.tsv" "$out/manifest.tsv"
$python scripts/field/field.py collect "$report"
$python scripts/field/field.py tables
echo "field: reports/field/ written (work in $report)"
exit 0
