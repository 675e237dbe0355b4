#!/usr/bin/env bash
# The OpenCL half of the map of where apccd's skipping pays (issue 37), on the GPU machine: scripts/apccd-map.sh
# PROFILE with BACKENDS=opencl and VERIFY=none. The exact truth is not computed there: the cells are verified
# afterwards by parity with the CPU map (`map.py OUT --parity CPU_MAP`: every step's answers digest must equal the
# verified CPU cell's). Builds nothing: runs device-carry/bin/ccdbench-after (CCDBENCH_BIN to change it).
# A call stops its run after LIMIT seconds (default 530, inside the device's 10-minute calls) and always packs what
# it has into $OUT: map-cells.tgz (the kept cells and their step records) and, once every cell is done,
# map-device.tgz (raw/map.json, raw/answers.tsv.gz, the command and the scene files). Carry map-cells.tgz back as
# device-carry/map-cells.tgz and call again: the next call resumes from it.
# Usage (in a device call, from the repository root): OUT=$OUT scripts/device-apccd-map.sh full
# Then here: tar xzf map-device.tgz -C reports/apccd-paper/PROFILE/ &&
#   /usr/bin/python3 reports/apccd-paper/map.py reports/apccd-paper/PROFILE/map-device --parity reports/apccd-paper/PROFILE/map
set -euo pipefail
cd "$(dirname "$0")/.."
profile=${1:-full}
out=/tmp/ccdbench-map-device
source scripts/device-env.sh
source scripts/device-builds.sh
cells=/tmp/ccdbench-map-cells
# A machine still warm from an earlier call keeps /tmp: its map folder is rebuilt from the cells (kept or carried),
# never packed as this call's.
rm -rf "$out/map-device"
mkdir -p "$cells"
[[ -f device-carry/map-cells.tgz ]] && tar xzf device-carry/map-cells.tgz -C "$cells"
pack() {
  tar czf "$OUT/map-cells.tgz" -C "$cells" .
  if [[ -f "$out/map-device/raw/answers.tsv.gz" ]]; then
    cp "$out/machine.txt" "$out/map-device/raw/machine.txt"
    tar czf "$OUT/map-device.tgz" -C "$out" map-device
    echo "map done"
  else
    echo "map not done: carry map-cells.tgz back as device-carry/map-cells.tgz and call again"
  fi
  ls -la "$OUT"
}
trap pack EXIT
write_machine after
CCDBENCH_BIN=${CCDBENCH_BIN:-device-carry/bin/ccdbench-after} BACKENDS=opencl VERIFY=none REPEATS=${REPEATS:-2} THREADS=$threads \
  OUT="$out/map-device" SHOWN_AS="reports/apccd-paper/$profile/map-device" CELLS="$cells" \
  timeout "${LIMIT:-530}" scripts/apccd-map.sh "$profile" 2>&1 | grep -v '^run: .*pass' || echo "apccd-map.sh stopped (status ${PIPESTATUS[0]})"
