#!/usr/bin/env bash
# Collects what a run on another Linux machine without ccdbench's packages needs into device-carry/ (ignored by
# git; `run`'s carry takes it to the device): bin/ccdbench (and bin/opencl_tests) of the release build, every shared library that it,
# OpenMPI's launcher and OpenMPI's plugins need (ldd; not libc, libm or the loader, which the machine has), and
# OpenMPI's and PMIx's plugins and help files under the paths Debian installs them to, below device-carry/root.
# scripts/device-env.sh sets the variables that point OpenMPI and PMIx there. Builds nothing.
# CARRY_VARIANTS="NAME=PATH ..." adds other ccdbench builds as bin/ccdbench-NAME (stripped), for runs that compare
# builds side by side (scripts/device-cpu-step.sh), with the release build's bvh and machine benchmarks; the
# OpenCL tests stay behind then, to keep the folder under run's 64 MiB.
# CARRY_STAGES="NAME=PATH ..." adds builds of benchmarks/conservative_stages as bin/conservative_stages-NAME
# (stripped), for the per-stage profile of each (device-opencl-scale.sh's part 'stages').
# CARRY_PLUGINS="FILE ..." adds plugins as plugins/FILE, with the shared libraries they need in lib/ (a CUDA plugin's
# libcudart: scripts/field/gpu.sh).
# Usage: scripts/device-carry.sh   (after scripts/build.sh release)
set -euo pipefail
cd "$(dirname "$0")/.."
carry=device-carry
rm -rf "$carry"
mkdir -p "$carry/bin" "$carry/lib" "$carry/root"
# (Not for a comparison of builds: its variants are carried instead.)
[ -n "${CARRY_VARIANTS:-}" ] || cp build/release/bin/ccdbench "$carry/bin/"
# The OpenCL parity tests, for scripts/device-opencl.sh (when the build has them).
if [ -x build/release/bin/opencl_tests ] && [ -z "${CARRY_VARIANTS:-}" ]; then cp build/release/bin/opencl_tests "$carry/bin/"; fi
for variant in ${CARRY_VARIANTS:-}; do
  strip -o "$carry/bin/ccdbench-${variant%%=*}" "${variant#*=}"
done
for variant in ${CARRY_STAGES:-}; do
  strip -o "$carry/bin/conservative_stages-${variant%%=*}" "${variant#*=}"
done
if [ -n "${CARRY_VARIANTS:-}" ]; then
  for benchmark in bvh_benchmark machine_benchmark; do strip -o "$carry/bin/$benchmark" "build/release/bin/$benchmark"; done
fi
# OpenMPI's launcher and plugins (not for a comparison of builds, which runs no MPI).
if [ -z "${CARRY_VARIANTS:-}" ]; then
  cp "$(readlink -f "$(command -v orterun)")" "$carry/bin/orterun"
  ln -s orterun "$carry/bin/mpirun"
  for tree in /usr/lib/x86_64-linux-gnu/openmpi/lib/openmpi3 /usr/share/openmpi /etc/openmpi \
              /usr/lib/x86_64-linux-gnu/pmix2/lib/pmix /usr/lib/x86_64-linux-gnu/pmix2/share; do
    mkdir -p "$carry/root$(dirname "$tree")"
    cp -rL "$tree" "$carry/root$tree"
  done
fi
for plugin in ${CARRY_PLUGINS:-}; do
  mkdir -p "$carry/plugins"
  cp "$plugin" "$carry/plugins/"
done
for binary in "$carry"/plugins/*.so "$carry"/bin/ccdbench "$carry"/bin/ccdbench-* "$carry"/bin/*_benchmark "$carry"/bin/conservative_stages-* "$carry"/bin/opencl_tests "$carry/bin/orterun" "$carry"/root/usr/lib/x86_64-linux-gnu/openmpi/lib/openmpi3/*.so \
              "$carry"/root/usr/lib/x86_64-linux-gnu/pmix2/lib/pmix/*.so; do
  [ -e "$binary" ] || continue
  ldd "$binary" | awk '$3 ~ /^\// {print $3}'
done | sort -u | grep -vE '/(libc|libm|libpthread|libdl|librt)\.so|ld-linux' | while read -r library; do
  cp -L "$library" "$carry/lib/"
done
# The public data (about 10 MB; scripts/data-dir.sh says where it is looked for) for the OpenCL parity tests and the
# public steps' timings.
source scripts/data-dir.sh
if [ -n "${CCDBENCH_DATA_DIR:-}" ]; then cp -r "$CCDBENCH_DATA_DIR" "$carry/data"; fi
du -sh "$carry"
