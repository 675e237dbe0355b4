#!/usr/bin/env bash
# Rebuilds reports/narrowphase/: every narrow phase (with its accuracy swept) and the reference on the public
# queries and on the extremes suite, in one run; the table, its JSON and the trade-off plot.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh release
data=${CCDBENCH_DATA_DIR:-../shared/data}
[[ -d $data ]] || data=data/external
out=reports/narrowphase
mkdir -p "$out"
build/release/bin/ccdbench stress --json "$out/stress.json" > "$out/stress.txt"
build/release/bin/ccdbench queries "$data/sample-queries" "$data/scalable-ccd-sample" --extremes \
  --method cubic32,cubic64,conservative,advancement,exact --sweep --repeat 3 --report "$out"
/usr/bin/python3 scripts/plot_narrowphase.py "$out/scores.json" "$out/tradeoff.png"
echo "narrowphase report: $out/README.md"
