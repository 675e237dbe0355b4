#!/usr/bin/env bash
# Builds ccdbench and runs every test. Usage: scripts/test.sh [release|debug|asan] (default: release).
# Set CCDBENCH_REQUIRE_DATA=1 to fail (not skip) the tests that need the public data (CI does).
set -euo pipefail
cd "$(dirname "$0")/.."
preset=${1:-release}
scripts/build.sh "$preset"
ctest --preset "$preset" -j "$(nproc)"
