#!/usr/bin/env bash
# Shows that the plugin boundary's tests can fail: for each guard of the plugin boundary (docs/DESIGN.md §10), builds
# ccdbench with that guard alone left out (CCDBENCH_PLUGIN_GUARDS_OFF=GUARD) into build/guards-off-GUARD, runs its tests
# (tests/plugins/boundary_test.cpp; the fork's in isolation_test.cpp, the gate's also in tests/harness/gate_test.cpp)
# and prints, per guard, each test and the first lines of its failure, as it must fail without its guard. Exits 0
# when every one of them failed, 1 when one passed. About two minutes per guard on 2 cores (a Release build without
# benchmarks).
# Usage: scripts/guards-off.sh [GUARD...]   (default: every guard)
# Such a build is for this and nothing else: its version line and every record's provenance say which guards are off.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh >/dev/null

declare -A tests=(
  [fenv]="Boundary.APluginBuiltWithFastMathChangesNoAnswerOfTheReferenceOrTheBuiltIns Boundary.ACallThatLeavesTheRoundingModeChangedIsThatCallsError"
  [input_copies]="Boundary.APluginThatWritesItsInputsChangesNoFrameOfTheRun"
  [exit]="Boundary.AnExitInsideACallEndsTheRunSayingSoOrIsTheCallsErrorIsolated"
  [chdir]="Boundary.AChdirInsideACallIsRefusedAndEveryOutputLandsWhereItWasNamed"
  [timeout]="Boundary.ACallPastItsTimeoutEndsAnInProcessRunNamingIt"
  [identity]="Boundary.RebuildingALibraryThePluginLinksMakesItAnotherPlugin"
  [child_identity]="Boundary.AFileReplacedDuringARunGivesNoAnswersUnderTheOldDigest"
  [describe_in_child]="Boundary.APluginWhoseLoadCrashesIsRefusedNotTheRunsCrash"
  [lifeline]="Boundary.AChildDiesWithItsParentEvenWhileThePluginHangs"
  [fork]="Isolation.APluginWhoseForkReturnsGivesNoOtherQuerysAnswer"
  [read_once]="Boundary.AnswersRewrittenWhileReadPutNoOtherDigestOnTheirVerdict Boundary.FoldersOfAnswersThatDifferHaveDifferentDigests"
  [repeats]="Boundary.AnswersThatChangeBetweenPassesAreAVerdictTheGateSees Boundary.ErrorsThatAppearInALaterPassAreNondeterminism"
  [gate]="Boundary.ErrorsCountedAsHitsStillFailTheGate Gate.ErrorsAndNondeterminismFailACellUnlessItsEntryAllowsThem"
)
order=(fenv input_copies exit chdir timeout identity child_identity describe_in_child lifeline fork read_once repeats gate)
guards=("$@")
if ((${#guards[@]} == 0)); then guards=("${order[@]}"); fi
for guard in "${guards[@]}"; do
  [[ -n ${tests[$guard]:-} ]] || { echo "guards-off: unknown guard '$guard' (known: ${order[*]})" >&2; exit 2; }
done

export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-$PWD/build/guards-off-cache}
all_failed=1
rows=()
for guard in "${guards[@]}"; do
  # One build per guard, with that guard alone left out: each test then fails for its own guard's reason.
  build=build/guards-off-$guard
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCCDBENCH_BUILD_BENCHMARKS=OFF "-DCCDBENCH_PLUGIN_GUARDS_OFF=$guard" >/dev/null 2>&1
  targets=(plugins_tests)
  [[ $guard == gate ]] && targets+=(harness_tests)
  cmake --build "$build" -j "$(nproc)" --target "${targets[@]}" >/dev/null
  echo "guards-off: $build: $("$build/bin/ccdbench" --version)"
  for test in ${tests[$guard]}; do
    binary=$build/bin/plugins_tests
    [[ $test == Gate.* ]] && binary=$build/bin/harness_tests
    # A test whose guard is off may hang (a reference in flush-to-zero may never finish): that is a failure too.
    if timeout 300 "$binary" --gtest_filter="$test" >"$build/$test.log" 2>&1; then
      result="PASSED (it should have failed: see $build/$test.log)"
      all_failed=0
    else
      result="FAILED: $(grep -m1 -A3 ': Failure' "$build/$test.log" | tail -n +2 | tr -s ' \n' ' ' | cut -c1-150 || true)"
      grep -q ': Failure' "$build/$test.log" || result="FAILED: $(tail -n 3 "$build/$test.log" | tr -s ' \n' ' ' | cut -c1-150 || true)"
    fi
    rows+=("$(printf '%-18s %-75s %s' "$guard" "$test" "$result")")
  done
done
printf '%-18s %-75s %s\n' guard test "without its guard"
printf '%s\n' "${rows[@]}"
if ((all_failed)); then
  echo "guards-off: every test failed without its guard (each passes in the normal build: scripts/test.sh)"
  exit 0
fi
echo "guards-off: a test passed without its guard: it does not show that guard" >&2
exit 1
