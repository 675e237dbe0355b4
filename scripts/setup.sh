#!/usr/bin/env bash
# Installs what a fresh Debian 12 machine lacks to build, test and run ccdbench: exactly the missing
# packages, all from the distribution. Safe to run again: it installs nothing when nothing is missing.
# Usage: scripts/setup.sh [EXTRA_PACKAGE...]   (scripts/fuzz.sh adds clang-14 and libclang-rt-14-dev; the scripts that
# draw plots, run.sh and narrowphase-report.sh, add python3-matplotlib, which building and testing do not need: CI,
# which runs the tests on a fresh machine, is spared its few dozen packages)
set -euo pipefail

packages=(
  g++ cmake ninja-build pkg-config git clang-format universal-ctags
  libeigen3-dev libtbb-dev libcgal-dev libgmp-dev libmpfr-dev
  libfcl-dev libccd-dev
  ocl-icd-opencl-dev opencl-headers pocl-opencl-icd
  libgtest-dev libgmock-dev libbenchmark-dev
  nlohmann-json3-dev libcli11-dev libxxhash-dev
  libopenmpi-dev openmpi-bin
  python3-dev pybind11-dev python3-numpy python3-pytest
  "$@"
)

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$package")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
sudo=()
if [[ $(id -u) -ne 0 ]]; then sudo=(sudo); fi
"${sudo[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
