#!/usr/bin/env bash
# Fetches the public data with exact ground truth into data/external (ignored by git), by commit, for users
# who have the network. The layout and counts are in docs/DATA.md. Tests find it there, or wherever
# CCDBENCH_DATA_DIR points.
# Usage: scripts/fetch-data.sh [--field]
#   --field: also the handcrafted and simulation sets of Sample-Queries (field-queries/, which reports/field/ scores;
#            no test reads them).
# CCDBENCH_FETCH_FROM=DIR takes each file from a local git copy of its repository, DIR/REPOSITORY (Sample-Queries,
# Sample-Scalable-CCD-Data), at the same commit, instead of the network; a file the copy lacks is named, and the
# script then exits with status 3 after fetching the rest.
set -euo pipefail
cd "$(dirname "$0")/.."
target=data/external
field=0
[ "${1:-}" = "--field" ] && field=1
missing=0
queries_repo=Continuous-Collision-Detection/Sample-Queries
queries_commit=a744562c7a842e9eee033fcea290e75a4a8e7b4e
scalable_repo=Continuous-Collision-Detection/Sample-Scalable-CCD-Data
scalable_commit=d1de594b017d98b37be67f02f74e541e74804109

[ -n "${CCDBENCH_FETCH_FROM:-}" ] || command -v curl >/dev/null || { echo "fetch-data: needs curl (apt-get install curl)" >&2; exit 1; }

fetch() {  # fetch REPO COMMIT PATH DESTINATION
  mkdir -p "$(dirname "$4")"
  if [ -n "${CCDBENCH_FETCH_FROM:-}" ]; then
    if git -C "$CCDBENCH_FETCH_FROM/${1#*/}" show "$2:$3" >"$4.part" 2>/dev/null; then
      mv "$4.part" "$4"
      echo "fetch-data: $4"
    else
      rm -f "$4.part"
      rmdir -p --ignore-fail-on-non-empty "$(dirname "$4")"
      echo "fetch-data: MISSING $3 at ${2:0:7}: not in $CCDBENCH_FETCH_FROM/${1#*/}" >&2
      missing=1
    fi
    return
  fi
  local url="https://raw.githubusercontent.com/$1/$2/$3"
  curl -fsSL --retry 3 -o "$4.part" "$url"
  # Large files may be stored with Git LFS: the raw file is then a pointer; fetch the media instead.
  if head -c 40 "$4.part" | grep -q "git-lfs.github.com/spec"; then
    curl -fsSL --retry 3 -o "$4.part" "https://media.githubusercontent.com/media/$1/$2/$3"
  fi
  mv "$4.part" "$4"
  echo "fetch-data: $4"
}

fetch "$queries_repo" "$queries_commit" LICENSE "$target/sample-queries/LICENSE"
for kind in edge-edge vertex-face; do
  for file in data_0_0.csv data_0_1.csv; do
    fetch "$queries_repo" "$queries_commit" "unit-tests/$kind/$file" "$target/sample-queries/unit-tests/$kind/$file"
  done
done

fetch "$scalable_repo" "$scalable_commit" LICENSE "$target/scalable-ccd-sample/LICENSE"
for scene_step in cloth-funnel:227:228 rod-twist:3036:3037; do
  IFS=: read -r scene step next <<<"$scene_step"
  base="$target/scalable-ccd-sample/$scene"
  fetch "$scalable_repo" "$scalable_commit" "$scene/frames/$step.ply" "$base/frames/$step.ply"
  fetch "$scalable_repo" "$scalable_commit" "$scene/frames/$next.ply" "$base/frames/$next.ply"
  for kind in vf ee; do
    fetch "$scalable_repo" "$scalable_commit" "$scene/boxes/$step$kind.json" "$base/boxes/$step$kind.json"
    fetch "$scalable_repo" "$scalable_commit" "$scene/queries/$step$kind.csv" "$base/queries/$step$kind.csv"
    fetch "$scalable_repo" "$scalable_commit" "$scene/mma_bool/${step}${kind}_mma_bool.json" \
      "$base/mma_bool/${step}${kind}_mma_bool.json"
  done
done
# The handcrafted and simulation sets of Wang et al. 2021's benchmark, as Sample-Queries samples them: every file of
# the same commit, kept apart from sample-queries/ (whose counts the data tests assert).
if [ "$field" = 1 ]; then
  for scene in erleben-cube-cliff-edges erleben-cube-internal-edges erleben-sliding-spike erleben-sliding-wedge erleben-spike-crack \
    erleben-spike-hole erleben-spike-wedge erleben-spikes erleben-wedge-crack erleben-wedges chain cow-heads golf-ball mat-twist; do
    case $scene in erleben-*) set_name=handcrafted ;; *) set_name=simulation ;; esac
    files="data_0_0.csv data_0_1.csv"
    [ "$scene" = erleben-spike-hole ] && files=data_0_0.csv
    for kind in edge-edge vertex-face; do
      for file in $files; do
        fetch "$queries_repo" "$queries_commit" "$scene/$kind/$file" "$target/field-queries/$set_name/$scene/$kind/$file"
      done
    done
  done
  fetch "$queries_repo" "$queries_commit" LICENSE "$target/field-queries/LICENSE"
fi
echo "fetch-data: done; check the counts with: build/release/bin/ccdbench inspect $target/sample-queries"
[ "$missing" = 0 ] || { echo "fetch-data: some files were missing (above)" >&2; exit 3; }
