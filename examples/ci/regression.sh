#!/usr/bin/env bash
# The regression check of a change to a CCD plugin, as CI runs it (ccdbench's docs/ci-regression.md): build
# ccdbench and the base and head versions of the plugin, run both in one invocation (same machine, same scenes, so
# their times compare too), gate the head against the baseline kept in its repository, and compare head with base.
#
#   examples/ci/regression.sh CCDBENCH_SOURCE BASE_SOURCE HEAD_SOURCE WORK
#
# CCDBENCH_SOURCE: a ccdbench checkout; BASE_SOURCE, HEAD_SOURCE: two checkouts of the plugin's project (the base
# branch and the change), each a CMake project that builds the plugin against an installed ccdbench (as the
# template, examples/plugin/, does); WORK: a folder for everything this writes. In WORK afterwards:
#   run.json, run/     the run's summaries and its --out folder (step records)
#   gate.txt           what `ccdbench check` said of the head
#   compare.md         the comparison as Markdown (the gate's verdict appended): the pull request's comment
#   compare.json       the comparison for scripts; replay/ the pairs the head newly misses, as query files
# Environment:
#   PLUGIN=libmy_ccd.so      the plugin's file, relative to its build folder
#   BASELINE                 the gate's baseline; default: BASE_SOURCE/ccdbench-baseline.json (the branch the change
#                            goes into decides what the change must meet), else HEAD_SOURCE's (the change that adds it)
#   RUN_ARGS                 what to run; default: the kinematic fold (generated into WORK/scenes) at its δ and at
#                            δ = 0, TOIs checked, REPEAT passes (default 9: base and head run in turn, pass by
#                            pass, and fewer than 6 pairs cannot show a time change at p < 0.05; with two cells
#                            compared, 9 can at 0.025 each).
#                            Paths in it are relative to WORK. Plugins cannot take scenes with analytic shapes (the
#                            ci suite has one).
#   WRITE_BASELINE=1         write BASELINE (default HEAD_SOURCE/ccdbench-baseline.json) from the head's results
#                            instead of gating; MARGIN=N or P% allows that much more
#   CCDBENCH=PATH            a ccdbench already installed (its bin/ccdbench): skips building ccdbench
#   BASE_BUILD, HEAD_BUILD   the plugin's two builds, already made: skips building them
#   PR_NUMBER                with the GitHub CLI (gh) and its token: posts compare.md on that pull request
# Where the base has no build of the plugin (the change that adds it), the head is gated alone and compare.md says so.
# Exit status: 0 when the gate passes and no verdict got worse, 1 when either failed, 2 for bad input (ccdbench's),
# 3 when compare found a cell it could not compare (another input, or times made elsewhere: ccdbench compare --help).
set -euo pipefail
if [[ $# -ne 4 ]]; then
  sed -n '5,7p' "$0" >&2
  exit 2
fi
ccdbench_source=$(realpath "$1")
base_source=$(realpath "$2")
head_source=$(realpath "$3")
mkdir -p "$4"
work=$(realpath "$4")
plugin=${PLUGIN:-libmy_ccd.so}
if [[ -n ${BASELINE:-} ]]; then
  baseline=$(realpath -m "$BASELINE")
elif [[ ${WRITE_BASELINE:-0} != 1 && -f $base_source/ccdbench-baseline.json ]]; then
  baseline=$base_source/ccdbench-baseline.json
else
  baseline=$head_source/ccdbench-baseline.json
fi
# This run's outputs only: a comparison or gate left from an earlier run in WORK is never posted as this one's.
rm -f "$work/run.json" "$work/gate.txt" "$work/compare.md" "$work/compare.json"

# 1. ccdbench, built (its Debian packages installed first) and installed into WORK/prefix, where the plugins'
#    find_package(ccdbench) finds it.
if [[ -n ${CCDBENCH:-} ]]; then
  ccdbench=$(realpath "$CCDBENCH")
  prefix=$(dirname "$(dirname "$ccdbench")")
else
  "$ccdbench_source/scripts/build.sh"
  cmake --install "$ccdbench_source/build/release" --prefix "$work/prefix" > /dev/null
  prefix=$work/prefix
  ccdbench=$prefix/bin/ccdbench
fi

# 2. The plugin's two versions, each in its own build folder: WORK/base and WORK/head. The run names them by these
#    relative paths (plugin:base/..., plugin:head/...), so the baseline's entries hold no machine's absolute path.
build_plugin() {  # SOURCE PREBUILT FOLDER; fails (status 1) when there is nothing to build
  rm -rf "${work:?}/$3"
  if [[ -n $2 ]]; then
    ln -sfn "$(realpath "$2")" "$work/$3"
  else
    [[ -f $1/CMakeLists.txt ]] || { echo "regression.sh: $1 has no CMakeLists.txt" >&2; return 1; }
    cmake -S "$1" -B "$work/$3" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" > "$work/$3.log" 2>&1 &&
      cmake --build "$work/$3" -j "$(nproc)" >> "$work/$3.log" 2>&1 || { tail -n 20 "$work/$3.log" >&2; return 1; }
  fi
  [[ -f $work/$3/$plugin ]] || { echo "regression.sh: $work/$3/$plugin: not built (set PLUGIN to its path in the build folder)" >&2; return 1; }
}
build_plugin "$head_source" "${HEAD_BUILD:-}" head || exit 2
with_base=0
if [[ ${WRITE_BASELINE:-0} != 1 ]]; then
  with_base=1
  build_plugin "$base_source" "${BASE_BUILD:-}" base || with_base=0
fi
base_spec=plugin:base/$plugin
head_spec=plugin:head/$plugin
specs=$head_spec
if ((with_base)); then specs=$base_spec,$head_spec; fi

# 3. One invocation runs both (and whatever else RUN_ARGS names). The plugins' cells are computed again every time,
#    even where WORK/run keeps one of the same code: a plugin's answers can depend on what no digest covers, and the
#    gate judges only answers given in this run (docs/DESIGN.md §10 "Kept cells"). Built-in strategies' cells are kept.
cd "$work"
if [[ -z ${RUN_ARGS:-} ]]; then
  [[ -f scenes/fold/scene.json ]] || "$ccdbench" generate fold --out scenes/fold > /dev/null
  RUN_ARGS="--scene scenes/fold --thickness scene,0 --toi --repeat ${REPEAT:-9}"
fi
# --interleave: the base's and the head's passes run in turn, so that a machine that slows down meanwhile slows both
# and compare tests their times pass by pass (docs/ci-regression.md, "Time verdicts").
# shellcheck disable=SC2086  # RUN_ARGS is a list of arguments
"$ccdbench" run $RUN_ARGS --strategy "$specs" --interleave --verify exact --json run.json --out run

# 4. The gate, of the head alone; or its baseline written.
if [[ ${WRITE_BASELINE:-0} == 1 ]]; then
  exec "$ccdbench" check --write-baseline "$baseline" --margin "${MARGIN:-0}" --strategy "$head_spec" run.json
fi
status=0
"$ccdbench" check --baseline "$baseline" --strategy "$head_spec" run.json > gate.txt 2>&1 || status=$?
cat gate.txt

# 5. The comparison of head with base, from the run's step records, and the gate's verdict under it.
if ((with_base)); then
  compared=0
  "$ccdbench" compare run run --pair "$base_spec" "$head_spec" --markdown compare.md --json compare.json --replay replay || compared=$?
  if ((compared > status)); then status=$compared; fi
else
  printf '### ccdbench compare\n\nThe base has no build of the plugin: the head was gated alone.\n' > compare.md
fi
if [[ -f compare.md ]]; then
  {
    echo
    echo '#### Gate (`ccdbench check`, head)'
    echo
    echo '```'
    cat gate.txt
    echo '```'
  } >> compare.md
  echo "regression.sh: the comparison for the pull request: $work/compare.md"
  if [[ -n ${PR_NUMBER:-} ]] && command -v gh > /dev/null; then
    gh pr comment "$PR_NUMBER" --body-file compare.md
  fi
fi
exit $status
