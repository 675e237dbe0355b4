# Sourced (after device-env.sh) by the scripts that compare ccdbench builds side by side on the GPU machine
# (device-narrowphase.sh, device-opencl-step.sh), with $out set to their work folder: registers the machine's NVIDIA
# OpenCL driver (installed there, not registered; where no nvidia-smi is, e.g. trying a script with PoCL, the
# registered devices stay), sets the cache and data folders, the builds' folder ($bin: bin/ccdbench-NAME, from
# CARRY_VARIANTS="NAME=PATH ..." scripts/device-carry.sh) and the thread count, and defines the helpers below.
mkdir -p "$out" /tmp/icd
if command -v nvidia-smi > /dev/null; then
  echo libnvidia-opencl.so.1 > /tmp/icd/nvidia.icd
  export OCL_ICD_VENDORS=/tmp/icd
fi
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-/tmp/ccdbench-cache}
export CCDBENCH_DATA_DIR=${CCDBENCH_DATA_DIR:-$PWD/device-carry/data}
threads=$(nproc)
bin=device-carry/bin
# write_machine VARIANT...: $out/machine.txt (cores, CPU, GPU and driver, each build's version line), also printed.
write_machine() {
  { nproc; lscpu | grep -E 'Model name|^CPU\(s\)' || true; nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader || true; } > "$out/machine.txt" 2>&1
  for v in "$@"; do echo "$v: $("$bin/ccdbench-$v" --version | head -1)"; done >> "$out/machine.txt"
  cat "$out/machine.txt"
}
# part NAME: whether $PARTS names it.
part() { [[ " $PARTS " == *" $1 "* ]]; }
# frames SCENE A B: the public step A -> B of the public data's scalable-ccd-sample (carried as device-carry/data), as run's --frames arguments.
frames() { echo "$CCDBENCH_DATA_DIR/scalable-ccd-sample/$1/frames/$2.ply $CCDBENCH_DATA_DIR/scalable-ccd-sample/$1/frames/$3.ply"; }
