#!/usr/bin/env bash
# The main job: builds ccdbench (Release) and runs it on the public data with exact ground truth.
# Extra arguments replace the default paths: scripts/run.sh path/to/scene.json
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh release
ccdbench=build/release/bin/ccdbench

if (($# > 0)); then
  exec "$ccdbench" inspect "$@"
fi

data=${CCDBENCH_DATA_DIR:-}
if [[ -z $data ]]; then
  for candidate in ../shared/data data/external; do
    if [[ -d $candidate ]]; then data=$candidate; break; fi
  done
fi
if [[ -z $data ]]; then
  echo "run: no public data found: set CCDBENCH_DATA_DIR or run scripts/fetch-data.sh" >&2
  exit 1
fi
"$ccdbench" inspect "$data/sample-queries" "$data/scalable-ccd-sample/cloth-funnel" \
  "$data/scalable-ccd-sample/rod-twist"
echo
"$ccdbench" queries "$data/sample-queries" "$data/scalable-ccd-sample" --method exact
echo
"$ccdbench" truth --sample "$data/scalable-ccd-sample/cloth-funnel"
