#!/usr/bin/env bash
# The regression check of a change to a CCD plugin, as CI runs it (ccdbench's README, "CI regression"): build
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
#   BASELINE=HEAD_SOURCE/ccdbench-baseline.json   the gate's baseline, kept in the plugin's repository
#   RUN_ARGS="--suite ci --toi --repeat 5"        what to run (scenes, δ); 5 passes let a time change be tested
#   WRITE_BASELINE=1         write BASELINE from the head's results instead of gating (MARGIN=N or P% allowed)
#   CCDBENCH=PATH            a ccdbench already installed (its bin/ccdbench): skips building ccdbench
#   BASE_BUILD, HEAD_BUILD   the plugin's two builds, already made: skips building them
#   PR_NUMBER                with the GitHub CLI (gh) and its token: posts compare.md on that pull request
# Exit status: 0 when the gate passes and no verdict got worse, 1 when either failed, 2 for bad input.
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
baseline=${BASELINE:-$head_source/ccdbench-baseline.json}
run_args=${RUN_ARGS:---suite ci --toi --repeat 5}

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
build_plugin() {  # SOURCE PREBUILT FOLDER
  if [[ -n $2 ]]; then
    ln -sfn "$(realpath "$2")" "$work/$3"
  else
    cmake -S "$1" -B "$work/$3" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" > /dev/null
    cmake --build "$work/$3" -j "$(nproc)" > /dev/null
  fi
  if [[ ! -f $work/$3/$plugin ]]; then
    echo "regression.sh: $work/$3/$plugin: not built (set PLUGIN to the library's path in its build folder)" >&2
    exit 2
  fi
}
build_plugin "$base_source" "${BASE_BUILD:-}" base
build_plugin "$head_source" "${HEAD_BUILD:-}" head
base_spec=plugin:base/$plugin
head_spec=plugin:head/$plugin

# 3. One invocation runs both (and whatever else RUN_ARGS names); cells already in WORK/run are kept.
cd "$work"
# shellcheck disable=SC2086  # RUN_ARGS is a list of arguments
"$ccdbench" run $run_args --strategy "$base_spec,$head_spec" --verify exact --json run.json --out run

# 4. The gate, of the head alone; or its baseline written.
status=0
if [[ ${WRITE_BASELINE:-0} == 1 ]]; then
  "$ccdbench" check --write-baseline "$baseline" --margin "${MARGIN:-0}" --strategy "$head_spec" run.json
  exit 0
fi
"$ccdbench" check --baseline "$baseline" --strategy "$head_spec" run.json | tee gate.txt || status=1

# 5. The comparison of head with base, from the run's step records, and the gate's verdict under it.
"$ccdbench" compare run run --pair "$base_spec" "$head_spec" --markdown compare.md --json compare.json --replay replay || status=1
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
exit $status
