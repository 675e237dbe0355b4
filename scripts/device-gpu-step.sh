#!/usr/bin/env bash
# One step on every GPU of a node (issue 66; reports/gpus/): the 1M-triangle contact-rich step of the large suite
# (spinning-ball at resolution 708, frames 26-27, and the step after it), with full:backend=opencl on one GPU
# (device=0) and on every GPU (device=all) in one invocation, at δ = 0 and the scene's δ, 3 passes, answers only
# (--verify none); the CPU's full on the first step for the digests. Prints ms per step of each, how many steps'
# answers digests (the reported pairs and their TOIs) are one GPU's, and whether the first step's is the CPU's.
# Writes OUT_DIR/{gpus,cpu}.json and their step records (*.results.jsonl). Builds nothing: scripts/device-carry.sh first.
# Usage: scripts/device-gpu-step.sh OUT_DIR
set -euo pipefail
out=${1:?usage: device-gpu-step.sh OUT_DIR}
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/scripts/device-ccdbench.sh"
nvidia_opencl
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-/tmp/ccdbench-gpu-step-cache}
mkdir -p "$out"
echo "machine: $(nproc) cores, $(nvidia-smi -L | wc -l) GPUs ($(nvidia-smi --query-gpu=name --format=csv,noheader | sort | uniq -c | xargs))"
"$bin" devices | grep -E '^[0-9]+:' || true
scene=/tmp/gpu-step-scene
[ -f "$scene/scene.json" ] || "$bin" generate spinning-ball --resolution 708 --frames 29 --first-frame 26 --out "$scene" > "$out/generate.txt"
# Kernels compiled once for each device set, outside the timed run.
"$bin" run --scene "$scene" --max-steps 1 --verify none --strategy full:backend=opencl:device=0,full:backend=opencl:device=all \
  --out /tmp/gpu-step-warm --fresh > /dev/null 2>&1
start=$(date +%s%N)
"$bin" run --scene "$scene" --verify none --thickness 0,scene --repeat 3 \
  --strategy full:backend=opencl:device=0,full:backend=opencl:device=all --out /tmp/gpu-step-gpus --fresh --json "$out/gpus.json" \
  > "$out/gpus.txt" 2> "$out/gpus.log"
echo "GPU run: $((($(date +%s%N) - start) / 1000000)) ms"
"$bin" run --scene "$scene" --verify none --thickness 0,scene --max-steps 1 --strategy full --out /tmp/gpu-step-cpu --fresh --json "$out/cpu.json" \
  > "$out/cpu.txt" 2> "$out/cpu.log"
cp /tmp/gpu-step-gpus/results.jsonl "$out/gpus.results.jsonl"
cp /tmp/gpu-step-cpu/results.jsonl "$out/cpu.results.jsonl"
python3 - "$out" << 'EOF'
import json, os, sys
out = sys.argv[1]
def steps(path):
    found = {}
    for line in open(path):
        r = json.loads(line)
        if r.get("record") == "step":
            device = r["strategy"].split(":device=")[1].split(":")[0] if ":device=" in r["strategy"] else "cpu"
            found[(device, r["thickness"], r["step"])] = (r["answers"], r["elementary_tests"])
    return found
gpus, cpu = steps(os.path.join(out, "gpus.results.jsonl")), steps(os.path.join(out, "cpu.results.jsonl"))
cells = json.load(open(os.path.join(out, "gpus.json")))
print("%-10s %-10s %-12s %-14s %s" % ("devices", "δ", "ms/step", "vs one GPU", "digests"))
one = {c["thickness"]: c["ms_per_step"] for c in cells if c["provenance"]["opencl_device_index"] == "0"}
for c in cells:
    device = c["provenance"]["opencl_device_index"]
    mine = {k: v for k, v in gpus.items() if k[0] == c["strategy"].split(":device=")[1].split(":")[0] and k[1] == c["thickness"]}
    same = all(cpu.get(("cpu", t, s)) in (None, v) for (_, t, s), v in mine.items())
    checked = sum(1 for (_, t, s) in mine if ("cpu", t, s) in cpu)
    first = [k for k in gpus if k[1] == c["thickness"] and k[0] != "cpu" and "+" not in k[0] and k[0] != "all"]
    as_one = sum(1 for (_, t, s), v in mine.items() if any(gpus[k] == v for k in first if k[2] == s))
    print("%-10s %-10.3g %-12.1f %-14s %s" % (device, c["thickness"], c["ms_per_step"], "%.2fx" % (one[c["thickness"]] / c["ms_per_step"]),
                                             "%d of %d steps as one GPU's; %s" % (as_one, len(mine), "%d step(s) as the CPU's full" % checked if same else "NOT the CPU's")))
EOF
