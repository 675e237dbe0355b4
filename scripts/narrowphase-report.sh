#!/usr/bin/env bash
# Rebuilds reports/narrowphase/: every narrow phase (with its accuracy swept) and the reference on the public
# queries and on the extremes suite, in one run; the table (with TOI accuracy), its JSON and the trade-off plot;
# then the same queries rescaled by 2^-960, 2^-530, 2^500 and 2^960 (and 2^0 beside them) under scales/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh python3-matplotlib  # for the plot
scripts/build.sh release
data=${CCDBENCH_DATA_DIR:-../shared/data}
[[ -d $data ]] || data=data/external
out=reports/narrowphase
mkdir -p "$out"
build/release/bin/ccdbench stress --json "$out/stress.json" > "$out/stress.txt"
build/release/bin/ccdbench queries "$data/sample-queries" "$data/scalable-ccd-sample" --extremes --toi \
  --method cubic32,cubic64,conservative,advancement,exact --sweep --repeat 3 --report "$out"
/usr/bin/python3 scripts/plot_narrowphase.py "$out/scores.json" "$out/tradeoff.png"
# The same queries rescaled exactly by powers of two (δ = 0 and the data's truth): FN, FP, ns per query and TOI error
# per scale, one report per scale.
for exponent in -960 -530 500 960; do
  build/release/bin/ccdbench queries "$data/sample-queries" "$data/scalable-ccd-sample" --extremes --toi \
    --method cubic64,conservative,advancement --scale-exponent "$exponent" --repeat 3 --report "$out/scales/2^$exponent"
done
build/release/bin/ccdbench queries "$data/sample-queries" "$data/scalable-ccd-sample" --extremes --toi \
  --method cubic64,conservative,advancement --repeat 3 --report "$out/scales/2^0"
echo "narrowphase report: $out/README.md, $out/scales/"
