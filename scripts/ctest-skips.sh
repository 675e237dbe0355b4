#!/usr/bin/env bash
# Lists the tests the last ctest run of a build skipped, once each, grouped by the reason each gave (the line after
# GoogleTest's "Skipped", or a script's "NAME: skipped: REASON"). Prints nothing when none was skipped.
# Usage: scripts/ctest-skips.sh BUILD_DIR   (scripts/test.sh calls it after ctest)
set -euo pipefail
log=$1/Testing/Temporary/LastTest.log
[ -f "$log" ] || exit 0
awk '
  /^[0-9]+\/[0-9]+ Testing: / { name = $0; sub(/^[0-9]+\/[0-9]+ Testing: /, "", name); want = 0; next }
  want { if (!(name in reason_of)) { reason_of[name] = $0; order[++n] = name } want = 0; next }
  /: Skipped$/ { want = 1; next }
  /^[A-Za-z_.]+: skipped: / { if (!(name in reason_of)) { line = $0; sub(/^[A-Za-z_.]+: skipped: /, "", line); reason_of[name] = line; order[++n] = name } }
  END {
    if (n == 0) exit
    for (i = 1; i <= n; ++i) { r = reason_of[order[i]]; if (!(r in count)) reasons[++m] = r; count[r]++; names[r] = names[r] "\n    " order[i] }
    print "Skipped tests (" n "), by reason:"
    for (j = 1; j <= m; ++j) print "  " reasons[j] " (" count[reasons[j]] "):" names[reasons[j]]
  }' "$log"
