#!/usr/bin/env bash
# Builds the field's public CCD libraries from pinned commits, and their ccdbench plugins (the adapters in
# examples/plugins/field/, examples/plugins/tight_inclusion/ and examples/plugins/scalable_ccd/), into one folder
# (reports/field/README.md).
#
# Usage: scripts/field/build.sh [--sources-only] [LIBRARY...]
#   LIBRARY: tight_inclusion ipc fprf msrf rp_bsc rrp tight_ccd interval exact_root_parity (the CPU ones, the default:
#            all of them), scalable_ccd (the GPU part: CUDA, built only when named, on a machine with nvcc; its
#            plugin runs where an NVIDIA GPU of compute capability 9.0 is, CCDBENCH_SCALABLE_CCD_ARCH for another)
#   --sources-only: find and check each library's sources, build nothing (what CI runs).
# Environment:
#   CCDBENCH_FIELD_SOURCES  a folder of local copies, one git repository (clone or bare mirror) per library, named as
#                           its repository (Tight-Inclusion, ipc-toolkit, Floating-Point-Root-Finder, ...): a machine
#                           without the internet builds from what it has. Unset: each repository is cloned from its URL
#                           into $CCDBENCH_FIELD_WORK/clones.
#   CCDBENCH_FIELD_COMMIT_<LIBRARY>    another commit of that library than its pin (e.g. CCDBENCH_FIELD_COMMIT_fprf=abc123)
#   CCDBENCH_FIELD_CHECKOUT_<LIBRARY>  a folder holding that library's sources as they are (a patched checkout): copied
#                                      and built instead of any commit (its `git describe --dirty` names it)
#   CCDBENCH_FIELD_WORK     where sources are extracted and built (default: build/field in the checkout)
#   CCDBENCH_FIELD_PLUGINS  where the plugins go (default: $CCDBENCH_FIELD_WORK/plugins), with MANIFEST.tsv
#   CCDBENCH_PREFIX         an installed ccdbench to build against (default: build/release installed into
#                           $CCDBENCH_FIELD_WORK/ccdbench)
# Prints one line per library: built (its plugins), or why not. Exit status: 0 every library with sources was built
# (a library whose dependency Debian 12 lacks is named and not counted); 3 some library's sources are missing (each
# named; the rest built); 1 a build failed (its log named). Dependencies are Debian 12 packages only, installed where
# missing by scripts/setup.sh (libspdlog-dev and libboost-dev besides ccdbench's); nothing else is downloaded.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=${CCDBENCH_FIELD_WORK:-$root/build/field}
plugins=${CCDBENCH_FIELD_PLUGINS:-$work/plugins}
sources_only=0
if [ "${1:-}" = "--sources-only" ]; then sources_only=1; shift; fi

# LIBRARY REPOSITORY COMMIT PATHS PLUGINS: PATHS is what is extracted ("." the whole tree; ipc-toolkit's notebooks are
# large and unused), PLUGINS the plugin files it gives.
pins() {
  cat <<'EOF'
tight_inclusion Continuous-Collision-Detection/Tight-Inclusion ca9a8c24fe91de3376d77975c5e9978f88e05794 . libtight_inclusion_plugin.so
ipc ipc-sim/ipc-toolkit af53a9def68170f94d4cd3eda211bb41126a43e1 src,LICENSE libipc_tight_inclusion_plugin.so,libipc_additive_plugin.so
fprf Continuous-Collision-Detection/Floating-Point-Root-Finder e5fe5c9767207df5047e375fb20180a665ae186f . libfprf_plugin.so
msrf Continuous-Collision-Detection/Minimum-Separation-Root-Finder 1aeb9ac0a404b43980bc82912fac836b720b609b . libmsrf_plugin.so
rp_bsc Continuous-Collision-Detection/Root-Parity-and-Bernstein-Sign-Classification 1686f79ca4b3c95979e2f6a96504d4562e44d3ce . libroot_parity_plugin.so,libbsc_plugin.so
rrp Continuous-Collision-Detection/Rational-Root-Parity 812f8cc6bdd6768b4a70291f411581c3544bb227 . librational_root_parity_plugin.so
tight_ccd Continuous-Collision-Detection/TightCCD 366384bac36ed1549d265e90c180fdd1beab42c6 . libtight_ccd_plugin.so
interval Continuous-Collision-Detection/Interval-Based 4237dfde4e3f0a757ac738d052423957e3c5d16b . libuirf_plugin.so,libirf_plugin.so
exact_root_parity Continuous-Collision-Detection/Exact-Root-Parity-CCD ded6440dd454c57042fd54ced2f805c4b4b64137 . -
scalable_ccd Continuous-Collision-Detection/Scalable-CCD 8f9347c1afc36f2dda17424c15ff5b68087fe8dc src,cmake,CMakeLists.txt,LICENSE libscalable_ccd_plugin.so
EOF
}
# ipc-toolkit v1.5.0 pins Tight-Inclusion 1.0.6 (cmake/recipes/tight_inclusion.cmake): its classes are built on that one.
ipc_tight_inclusion=7377d78162f9fdb5fe44b54b6f9c01bc6ce0885a
# CCD-Wrapper's pin of root parity and BSC (1686f79, since its commit a988f00 of 2021-09) is on no branch of the
# repository any more; before that commit CCD-Wrapper pinned 8db61b2, the branch's head, which is built where 1686f79
# cannot be found (the line says so).
rp_bsc_fallback=8db61b2c1d399f19e73e4a16373e7a869cc95ad4

say() { printf '%-18s %s\n' "$1" "$2"; }

# The local copy of REPOSITORY, or a clone of it; "" when there is none. Its git directory is printed.
repository() {
  local name=${1#*/}
  if [ -n "${CCDBENCH_FIELD_SOURCES:-}" ]; then
    for candidate in "$CCDBENCH_FIELD_SOURCES/$name" "$CCDBENCH_FIELD_SOURCES/$name.git"; do
      if git -C "$candidate" rev-parse --git-dir >/dev/null 2>&1; then
        (cd "$candidate" && cd "$(git rev-parse --git-dir)" && pwd)
        return
      fi
    done
    return
  fi
  local clone=$work/clones/$name
  if [ ! -d "$clone" ] && [ "$sources_only" = 0 ]; then
    git clone --quiet --bare "https://github.com/$1" "$clone" >/dev/null 2>&1 || rm -rf "$clone"
  fi
  [ -d "$clone" ] && echo "$clone"
}

has_commit() { git --git-dir="$1" cat-file -e "$2^{commit}" 2>/dev/null; }

# Extracts PATHS of COMMIT from the git directory GIT into DEST (a fresh folder), or copies a checkout as it is.
extract() {
  local git=$1 commit=$2 paths=$3 dest=$4
  rm -rf "$dest" && mkdir -p "$dest"
  if [ "$commit" = "checkout" ]; then
    (cd "$git" && tar -c --exclude=.git .) | tar -x -C "$dest"
  else
    # shellcheck disable=SC2086
    git --git-dir="$git" archive "$commit" ${paths//,/ } | tar -x -C "$dest"
  fi
}

# The changes a library needs to compile on Debian 12 (GCC 12, Eigen 3.4), made to the extracted copy, never to
# the library's repository; each is said in MANIFEST.tsv and in the report. Each is idempotent, so that a patched
# checkout that already has it is left as it is.
patch_library() {
  local library=$1 dest=$2 applied=()
  case $library in
    rp_bsc)
      # expansion.h uses std::size_t without <cstddef>, which GCC 12's headers no longer bring in.
      if ! grep -q '#include <cstddef>' "$dest/expansion.h"; then
        sed -i '0,/^#include/s//#include <cstddef>\n#include/' "$dest/expansion.h"
        applied+=("expansion.h: #include <cstddef>")
      fi
      ;;
    interval)
      # interval.hpp declares Eigen::Vector<T, dim, max_dim>, which Eigen 3.4 now declares itself (Vector<T, Size>):
      # the library's alias is renamed where it is declared and where it is used.
      if grep -q 'using Vector = ' "$dest/intervalccd/interval.hpp"; then
        sed -i 's/using Vector = /using IntervalVector = /' "$dest/intervalccd/interval.hpp"
        sed -i 's/Eigen::Vector<Interval, dim, max_dim>/Eigen::IntervalVector<Interval, dim, max_dim>/' "$dest/intervalccd/interval_root_finder.cpp"
        applied+=("interval.hpp, interval_root_finder.cpp: Eigen::Vector alias renamed IntervalVector (Eigen 3.4 has its own)")
      fi
      ;;
  esac
  local IFS=';'
  echo "${applied[*]:-none}"
}

install_ccdbench() {
  if [ -n "${CCDBENCH_PREFIX:-}" ]; then echo "$CCDBENCH_PREFIX"; return; fi
  if [ ! -f "$root/build/release/bin/ccdbench" ]; then
    echo "field: no ccdbench to build against: build it first (scripts/build.sh) or set CCDBENCH_PREFIX" >&2
    exit 2
  fi
  cmake --install "$root/build/release" --prefix "$work/ccdbench" >/dev/null
  echo "$work/ccdbench"
}

wanted=("$@")
# With no LIBRARY named, the CPU libraries; the GPU one only when named.
wants() {
  if [ ${#wanted[@]} -eq 0 ]; then [ "$1" != scalable_ccd ]; else printf '%s\n' "${wanted[@]}" | grep -qx "$1"; fi
}
for w in "${wanted[@]}"; do
  pins | awk '{print $1}' | grep -qx "$w" || { echo "field: $w: not a library (one of: $(pins | awk '{print $1}' | tr '\n' ' '))" >&2; exit 2; }
done

prefix=""
if [ "$sources_only" = 0 ]; then
  # The libraries' dependencies beyond ccdbench's: Debian 12's spdlog (Tight-Inclusion, ipc-toolkit) and Boost
  # (Interval-Based), installed only where missing.
  "$root/scripts/setup.sh" libspdlog-dev libboost-dev >&2
  mkdir -p "$work" "$plugins"
  prefix=$(install_ccdbench)
fi
manifest=$plugins/MANIFEST.tsv
[ "$sources_only" = 1 ] || [ -f "$manifest" ] || printf 'library\trepository\tcommit\tplugins\tpatches\n' >"$manifest"
missing=0 failed=0
while read -r library repo pinned paths files; do
  wants "$library" || continue
  commit_var=CCDBENCH_FIELD_COMMIT_$library checkout_var=CCDBENCH_FIELD_CHECKOUT_$library
  commit=${!commit_var:-$pinned}
  if [ -n "${!checkout_var:-}" ]; then
    git_dir=${!checkout_var} commit=checkout
    [ -d "$git_dir" ] || { say "$library" "MISSING: $checkout_var=$git_dir is not a folder"; missing=1; continue; }
    described=$(git -C "$git_dir" describe --always --dirty 2>/dev/null || echo "not a git checkout")
  else
    git_dir=$(repository "$repo")
    if [ -z "$git_dir" ]; then
      if [ -n "${CCDBENCH_FIELD_SOURCES:-}" ]; then
        where="no git repository $CCDBENCH_FIELD_SOURCES/${repo#*/}"
      elif [ "$sources_only" = 1 ]; then
        where="CCDBENCH_FIELD_SOURCES is unset and $work/clones has none"
      else
        where="cloning https://github.com/$repo failed"
      fi
      say "$library" "MISSING: no copy of $repo ($where)"
      missing=1
      continue
    fi
    if ! has_commit "$git_dir" "$commit"; then
      if [ "$library" = rp_bsc ] && [ "$commit" = "$pinned" ] && has_commit "$git_dir" "$rp_bsc_fallback"; then
        commit=$rp_bsc_fallback
        say "$library" "pinned ${pinned:0:7} is not in $git_dir: building ${commit:0:7}, CCD-Wrapper's pin before a988f00"
      else
        say "$library" "MISSING: commit ${commit:0:7} is not in $git_dir"
        missing=1
        continue
      fi
    fi
    described=$commit
  fi
  if [ "$library" = exact_root_parity ]; then
    say "$library" "NOT BUILT: its libraries need libigl 2.3 (igl::predicates' orient3d/orient2d and igl::Timer, cmake/recipes/libigl.cmake), which Debian 12 does not package (sources found: ${described:0:7})"
    continue
  fi
  if [ "$library" = ipc ] && ! has_commit "$(repository Continuous-Collision-Detection/Tight-Inclusion)" "$ipc_tight_inclusion"; then
    say "$library" "MISSING: Tight-Inclusion ${ipc_tight_inclusion:0:7} (1.0.6, which ipc-toolkit pins) is not in its copy"
    missing=1
    continue
  fi
  if [ "$library" = scalable_ccd ] && [ "$sources_only" = 0 ] && ! command -v nvcc >/dev/null; then
    say "$library" "NOT BUILT: no CUDA compiler (nvcc on PATH) on this machine (sources found: ${described:0:7})"
    continue
  fi
  if [ "$sources_only" = 1 ]; then
    say "$library" "sources found: ${described:0:12} in $git_dir"
    continue
  fi

  src=$work/src/$library build=$work/build/$library log=$work/logs/$library.log
  mkdir -p "$work/logs"
  # Extracted again only for another commit or other patches (a checkout: every time).
  stamp="$described $paths $(declare -f patch_library | sha256sum | cut -c1-16)"
  if [ "$(cat "$src.stamp" 2>/dev/null)" != "$stamp" ] || [ "$commit" = checkout ]; then
    extract "$git_dir" "$commit" "$paths" "$src"
    if [ "$library" = ipc ]; then
      extract "$(repository Continuous-Collision-Detection/Tight-Inclusion)" "$ipc_tight_inclusion" . "$work/src/ipc-tight-inclusion"
    fi
    patches=$(patch_library "$library" "$src")
    echo "$patches" >"$src.patches"
    echo "$stamp" >"$src.stamp"
  fi
  patches=$(cat "$src.patches")
  if [ "$library" = tight_inclusion ]; then
    args=(-S "$root/examples/plugins/tight_inclusion" -DTIGHT_INCLUSION_DIR="$src")
  elif [ "$library" = scalable_ccd ]; then
    args=(-S "$root/examples/plugins/scalable_ccd" -DSCALABLE_CCD_DIR="$src" -DSCALABLE_CCD_COMMIT="${described:0:12}"
      -DSCALABLE_CCD_CUDA_ARCHITECTURES="${CCDBENCH_SCALABLE_CCD_ARCH:-90}")
  else
    args=(-S "$root/examples/plugins/field" -DFIELD_LIBRARY="$library" -DFIELD_LIBRARY_DIR="$src" -DFIELD_LIBRARY_COMMIT="${described:0:12}")
  fi
  [ "$library" = ipc ] && args+=(-DTIGHT_INCLUSION_DIR="$work/src/ipc-tight-inclusion")
  if ! { cmake "${args[@]}" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" &&
    nice -n 5 cmake --build "$build" -j "${CCDBENCH_FIELD_JOBS:-2}"; } >"$log" 2>&1; then
    say "$library" "FAILED to build ${described:0:7}: see $log"
    tail -n 5 "$log" | sed 's/^/    /'
    failed=1
    continue
  fi
  built=()
  for file in ${files//,/ }; do
    cp "$build/$file" "$plugins/$file"
    if ! "$prefix/bin/ccdbench" strategies --plugin "$plugins/$file" >/dev/null 2>>"$log"; then
      say "$library" "FAILED: ccdbench refuses $plugins/$file: see $log"
      failed=1
    fi
    built+=("$file")
  done
  grep -v "^$library	" "$manifest" >"$manifest.new" || true
  printf '%s\t%s\t%s\t%s\t%s\n' "$library" "$repo" "${described:0:12}" "${built[*]}" "$patches" >>"$manifest.new"
  mv "$manifest.new" "$manifest"
  say "$library" "built ${described:0:7}: ${built[*]} (patches: $patches)"
done < <(pins)

if [ "$sources_only" = 0 ]; then echo "field: plugins in $plugins (list one's keys: ccdbench strategies --plugin $plugins/FILE)"; fi
[ "$failed" = 0 ] || exit 1
[ "$missing" = 0 ] || exit 3
