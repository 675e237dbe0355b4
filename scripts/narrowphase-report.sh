#!/usr/bin/env bash
# Rebuilds reports/narrowphase/: every narrow phase (with its accuracy swept) and the reference on the public
# queries and on the extremes suite, in one run; the table (with TOI accuracy), its JSON and the trade-off plot;
# then the same queries rescaled by 2^-960, 2^-530, 2^500 and 2^960 (and 2^0 beside them) under scales/; with
# BEFORE=PATH (a ccdbench built from an earlier commit), before-after.md too.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh python3-matplotlib  # for the plot
scripts/build.sh release
source scripts/data-dir.sh
data=${CCDBENCH_DATA_DIR:?"no public data: run scripts/fetch-data.sh, or set CCDBENCH_DATA_DIR"}
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
# Before and after (BEFORE=path to a ccdbench built from an earlier commit): the same queries, each default variant,
# the earlier build and this one alternately in one invocation, at 2^0, 2^-960 and 2^960.
if [ -n "${BEFORE:-}" ]; then
  work=$(mktemp -d)
  {
    echo "# Narrow phases before and after"
    echo
    echo "Each default variant on the same queries (the public queries and the extremes suite, their truth at δ = 0),"
    echo "the earlier build ($("$BEFORE" --version | head -1)) and this one ($(build/release/bin/ccdbench --version | head -1))"
    echo "alternately in one invocation of \`BEFORE=... scripts/narrowphase-report.sh\` on $(nproc) cores of"
    echo "$(lscpu | sed -n 's/^Model name: *//p' | head -1); ns per query is the median of 3 repeats. Before → after."
    echo
    for exponent in 0 -960 960; do
      for side in before after; do
        binary=build/release/bin/ccdbench
        [ "$side" = before ] && binary=$BEFORE
        "$binary" queries "$data/sample-queries" "$data/scalable-ccd-sample" --extremes --toi \
          --method cubic32,cubic64,conservative,advancement --scale-exponent "$exponent" --repeat 3 --json "$work/$side-$exponent.json" > /dev/null
      done
      /usr/bin/python3 scripts/narrowphase_before_after.py "every query file and the extremes suite, scaled by 2^$exponent" \
        "$work/before-$exponent.json" "$work/after-$exponent.json"
    done
  } > "$out/before-after.md"
  rm -rf "$work"
fi
echo "narrowphase report: $out/README.md, $out/scales/"
