#!/usr/bin/env bash
# Every GPU of one node at work (issue 66; reports/gpus/): the paper suite with full and full+cubic64 on the OpenCL
# backend (--verify none: times and answers only), as one process with every core and as one MPI rank per GPU with
# the cores shared out, in one invocation. Prints the wall time of each, which device each rank's cells ran on (from
# the records), each GPU's busiest 100 ms (nvidia-smi, sampled while the run ran), and whether every cell's answers
# (reported pairs and elementary tests, step by step) are the same as one process's. Builds nothing: run
# scripts/device-carry.sh first (the device machine has no OpenMPI of its own).
# Usage: scripts/device-gpus.sh OUT_DIR   (SUITE=paper, RANKS="1 GPUS": the rank counts to run, STRATEGY: the specs,
#        e.g. with device=0 to put every rank on one GPU as before; THICKNESS=scene: the δ list, e.g. scene,0 for the
#        issue's sweep of 36 cells with STRATEGY=full:backend=opencl,full+cubic64:backend=opencl,apccd:backend=opencl;
#        THREADS: each rank's worker threads, the machine's cores shared out over the ranks if not given)
set -euo pipefail
out=${1:?usage: device-gpus.sh OUT_DIR}
root=$(cd "$(dirname "$0")/.." && pwd)
source "$root/scripts/device-ccdbench.sh"
nvidia_opencl
suite=${SUITE:-paper}
cores=$(nproc)
gpus=$(nvidia-smi -L | wc -l)
strategy=${STRATEGY:-full:backend=opencl,full+cubic64:backend=opencl}
thickness=${THICKNESS:-scene}
export CCDBENCH_CACHE_DIR=${CCDBENCH_CACHE_DIR:-/tmp/ccdbench-gpus-cache}
mkdir -p "$out"
echo "machine: $cores cores, $gpus GPUs ($(nvidia-smi --query-gpu=name --format=csv,noheader | sort | uniq -c | xargs)); $("$bin" --version)"
"$bin" devices | grep -E '^[0-9]+:' || true
# Warm: the suite's frames generated and the kernels compiled once, outside the timed runs.
"$bin" --threads "$cores" run --suite "$suite" --strategy "$strategy" --thickness "$thickness" --verify none --max-steps 1 --fresh --out /tmp/gpus-warm > /dev/null 2>&1
stamp() {  # each line of stdin after the ms since $1 (date +%s%N)
  local line now
  while IFS= read -r line; do
    now=${EPOCHREALTIME/./}
    printf '%6d %s\n' $(((now * 1000 - $1) / 1000000)) "$line"
  done
}
printf '%-6s %-8s %-10s %-24s %s\n' ranks threads wall_ms "devices by rank" "busiest 100 ms per GPU (%)"
for ranks in ${RANKS:-1 $gpus}; do
  threads=${THREADS:-$((cores / ranks))}
  name=r$ranks-t$threads
  if [[ $ranks == 1 ]]; then
    launch=("$bin" --threads "$threads")
  else
    launch=(mpirun -n "$ranks" --oversubscribe --bind-to none "$bin" --threads "$threads")
  fi
  # An empty --out: a folder an earlier run left cells in makes the run rebuild results.jsonl from them, at its first
  # cell and at its end (0.35 s each for this sweep's 36 cells), which is not this run's work.
  rm -rf "/tmp/gpus-$name"
  nvidia-smi --query-gpu=index,utilization.gpu --format=csv,noheader,nounits -lms 100 > "$out/$name.smi" &
  sampler=$!
  start=$(date +%s%N)
  # The log's lines with the ms since the launch: when each cell ended, on which rank.
  "${launch[@]}" run --suite "$suite" --strategy "$strategy" --thickness "$thickness" --verify none --fresh --out "/tmp/gpus-$name" --json "$out/$name.json" \
    2>&1 > "$out/$name.txt" | stamp "$start" > "$out/$name.log"
  wall=$((($(date +%s%N) - start) / 1000000))
  echo "$wall" > "$out/$name.wall"
  kill "$sampler" 2> /dev/null || true
  wait "$sampler" 2> /dev/null || true
  devices=$(python3 - "$out/$name.json" << 'EOF'
import json, sys
by_rank = {}
for cell in json.load(open(sys.argv[1])):
    by_rank.setdefault(cell["rank"], set()).add(cell["provenance"].get("opencl_device_index", "?"))
print(" ".join("r%d:%s" % (r, "+".join(sorted(d))) for r, d in sorted(by_rank.items())))
EOF
  )
  busiest=$(awk -F', *' '{ if ($2 > m[$1]) m[$1] = $2 } END { for (g in m) printf "gpu%s:%s ", g, m[g] }' "$out/$name.smi")
  printf '%-6s %-8s %-10s %-24s %s\n' "$ranks" "$threads" "$wall" "$devices" "$busiest"
done
# The same answers whatever the rank count: each cell's reported pairs and elementary tests, step by step.
python3 - "$out" ${RANKS:-1 $gpus} << 'EOF'
import json, os, sys
out, ranks = sys.argv[1], sys.argv[2:]
def answers(path):
    return {(c["scene"], c["strategy"], c["thickness"]): (c["reported"], c["elementary_tests"]) for c in json.load(open(path))}
runs = {}
for r in ranks:
    name = [f for f in os.listdir(out) if f.startswith("r%s-" % r) and f.endswith(".json")][0]
    runs[r] = answers(os.path.join(out, name))
base = runs[ranks[0]]
for r, cells in runs.items():
    same = cells == base
    print("answers with %s rank(s): %d cells, %s as one process's" % (r, len(cells), "the same" if same else "NOT the same"))
EOF
# Where each run's time went, from its records: every cell's start (setup_ms: making the strategy, its init on the
# first frame) and its timed steps, summed over the cells (over every rank's); each rank's own work (its cells' starts
# and steps) against the wall time; and from the stamped log, when the first and the last cell ended.
python3 - "$out" << 'EOF2'
import glob, json, os, re, statistics, sys
for path in sorted(glob.glob(os.path.join(sys.argv[1], "r*-t*.json"))):
    name = path[:-5]
    cells = json.load(open(path))
    setup = [c.get("setup_ms", 0.0) for c in cells]
    steps = [c["ms_per_step_mean"] * c["steps"] * c.get("repeats", 1) for c in cells]
    timed = sum(steps)
    own = {}
    for c, start, stepped in zip(cells, setup, steps):
        own[c["rank"]] = own.get(c["rank"], 0.0) + start + stepped
    wall = float(open(name + ".wall").read()) if os.path.exists(name + ".wall") else float("nan")
    ends = [int(line.split()[0]) for line in open(name + ".log") if re.search(r"pass \d+ of \d+ done|: cell \d+ of \d+ done", line)] if os.path.exists(name + ".log") else []
    print("%s: %d cells; their starts %.1f s (median %.0f ms, max %.0f ms); their timed steps %.1f s; each rank's own work %s s of %.1f s wall" % (
        os.path.basename(name), len(cells), sum(setup) / 1e3, statistics.median(setup), max(setup), timed / 1e3,
        "/".join("%.1f" % (v / 1e3) for _, v in sorted(own.items())), wall / 1e3))
    if ends:
        print("   first cell ended at %.1f s, last at %.1f s" % (min(ends) / 1e3, max(ends) / 1e3))
EOF2
