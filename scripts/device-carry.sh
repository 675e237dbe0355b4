#!/usr/bin/env bash
# Collects what a run on another Linux machine without ccdbench's packages needs into device-carry/ (ignored by
# git; `run`'s carry takes it to the device): bin/ccdbench of the release build, every shared library that it,
# OpenMPI's launcher and OpenMPI's plugins need (ldd; not libc, libm or the loader, which the machine has), and
# OpenMPI's and PMIx's plugins and help files under the paths Debian installs them to, below device-carry/root.
# scripts/device-env.sh sets the variables that point OpenMPI and PMIx there. Builds nothing.
# Usage: scripts/device-carry.sh   (after scripts/build.sh release)
set -euo pipefail
cd "$(dirname "$0")/.."
carry=device-carry
rm -rf "$carry"
mkdir -p "$carry/bin" "$carry/lib" "$carry/root"
cp build/release/bin/ccdbench "$carry/bin/"
cp "$(readlink -f "$(command -v orterun)")" "$carry/bin/orterun"
ln -s orterun "$carry/bin/mpirun"
for tree in /usr/lib/x86_64-linux-gnu/openmpi/lib/openmpi3 /usr/share/openmpi /etc/openmpi \
            /usr/lib/x86_64-linux-gnu/pmix2/lib/pmix /usr/lib/x86_64-linux-gnu/pmix2/share; do
  mkdir -p "$carry/root$(dirname "$tree")"
  cp -rL "$tree" "$carry/root$tree"
done
for binary in "$carry/bin/ccdbench" "$carry/bin/orterun" "$carry"/root/usr/lib/x86_64-linux-gnu/openmpi/lib/openmpi3/*.so \
              "$carry"/root/usr/lib/x86_64-linux-gnu/pmix2/lib/pmix/*.so; do
  ldd "$binary" | awk '$3 ~ /^\// {print $3}'
done | sort -u | grep -vE '/(libc|libm|libpthread|libdl|librt)\.so|ld-linux' | while read -r library; do
  cp -L "$library" "$carry/lib/"
done
du -sh "$carry"
