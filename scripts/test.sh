#!/usr/bin/env bash
# Builds ccdbench (Release) and runs every test. Set CCDBENCH_REQUIRE_DATA=1 to fail (not skip) the tests
# that need the public data (CI does).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh release
ctest --preset release -j "$(nproc)"
