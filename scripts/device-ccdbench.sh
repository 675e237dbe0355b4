# Sourced by the device scripts (scripts/device-*.sh, scripts/field/gpu.sh) after they set `root` (the checkout):
# sets `bin` to the ccdbench they run, the carried one (scripts/device-carry.sh, with scripts/device-env.sh's
# variables for its libraries and OpenMPI) where device-carry/ holds one, else the release build (with OpenMPI
# allowed to run as root, as the device machine runs). `nvidia_opencl` registers NVIDIA's OpenCL driver, which the
# device machine has installed but not registered (PoCL is then not listed: call it only where a GPU is wanted).
# shellcheck shell=bash disable=SC2034,SC2154
if [[ -x "$root/device-carry/bin/ccdbench" ]]; then
  source "$root/scripts/device-env.sh"
  bin="$root/device-carry/bin/ccdbench"
else
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
  bin="$root/build/release/bin/ccdbench"
fi
nvidia_opencl() {
  mkdir -p /tmp/icd && echo libnvidia-opencl.so.1 > /tmp/icd/nvidia.icd && export OCL_ICD_VENDORS=/tmp/icd
}
