#!/usr/bin/env bash
# reports/shapes: obstacles=shape against obstacles=mesh at paper scale (spinning-ball and drape at resolution 100,
# pile at 64, 100 frames each), full and apccd, every step verified against the exact truth at the scene's δ.
# Writes OUT/SCENE/summary.json (one record per scene and strategy) and OUT/SCENE/results.jsonl (every step);
# reports/shapes/tables.py renders README.md's tables from them.
# Usage: reports/shapes/run.sh [OUT]   (default reports/shapes/results)
#   CCDBENCH_BIN     the ccdbench to run (default build/release/bin/ccdbench)
#   SHAPES_SCENES    which scenes (default "spinning-ball drape pile")
#   SHAPES_FRAMES    frames per scene (default 100)
set -euo pipefail
cd "$(dirname "$0")/../.."
bin=${CCDBENCH_BIN:-build/release/bin/ccdbench}
out=${1:-reports/shapes/results}
frames=${SHAPES_FRAMES:-100}
for scene in ${SHAPES_SCENES:-spinning-ball drape pile}; do
  resolution=100
  [ "$scene" = pile ] && resolution=64
  files=()
  for obstacles in mesh shape; do
    folder=$out/scenes/$scene-$obstacles
    mkdir -p "$folder"
    printf '{"generator": {"name": "%s", "resolution": %d, "frames": %d, "obstacles": "%s"}}\n' \
      "$scene" "$resolution" "$frames" "$obstacles" > "$folder/scene.json"
    files+=("$folder/scene.json")
  done
  echo "== $scene (resolution $resolution, $frames frames): obstacles=mesh and obstacles=shape"
  "$bin" run --scene "${files[@]}" --strategy full,apccd --out "$out/$scene" --json "$out/$scene/summary.json"
done
