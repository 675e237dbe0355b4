#!/usr/bin/env python3
"""Issue 51's tables (reports/narrowphase/resting/README.md): conservative's step time over cubic64's on resting
contact, each build side by side, from one device invocation's folders:
  SCALE: scripts/device-opencl-scale.sh's folder (PARTS="fits cpu"): fits-ball-NARROW-VARIANT (the OpenCL step,
         the 1M-triangle ball's steps 2-15, of which 2, 10 and 14 are shown), fits-{rod-twist,cloth-funnel}-...,
         cpu-step-{10,14}-VARIANT and cpu-paper-ball-VARIANT (the CPU, `full` and `full+cubic64` in one process);
  STEP:  scripts/device-opencl-step.sh's folder (PARTS="... ball"): ball-VARIANT-NARROW (the OpenCL step on the
         paper's spinning ball, 99 steps).
ms per step is the harness's (the median of a step's passes); for a scene, the median and the mean over its steps.
Usage: table.py SCALE STEP [VARIANT ...] (default: before after)"""

import gzip
import json
import os
import statistics
import sys

# Step k of the fits run is frame 2 + k -> 3 + k.
BALL_STEPS = {2: 0, 10: 8, 14: 12}


def steps(path, strategy_prefix=None):
    """The step records of a kept run (PATH.jsonl.gz), by step; only those of one strategy when asked."""
    if not os.path.exists(path + ".jsonl.gz"):
        return None
    records = []
    with gzip.open(path + ".jsonl.gz", "rt") as lines:
        for line in lines:
            record = json.loads(line)
            if record.get("record") != "step":
                continue
            if strategy_prefix is not None and record["strategy"].split(":")[0] != strategy_prefix:
                continue
            records.append(record)
    return sorted(records, key=lambda r: r["step"])


def stage(record, name):
    return record["stages"].get(name, 0.0)


def gpu_ball(folder, variants):
    print("OpenCL step, the 1M-triangle ball at the scene's δ: ms per step (narrow phase ms; host narrow phase ms;")
    print("queries given up / in the second pass / in the third), conservative over cubic64, and whether each build's")
    print("answers digest equals the first build's")
    print("| step | build | conservative ms | cubic64 ms | conservative / cubic64 | narrow phase ms | host narrow phase ms | given up / second / third | digest |")
    print("|---:|---|---:|---:|---:|---:|---:|---|---|")
    runs = {v: (steps(os.path.join(folder, f"fits-ball-conservative-{v}")), steps(os.path.join(folder, f"fits-ball-cubic64-{v}"))) for v in variants}
    for label, k in BALL_STEPS.items():
        first = None
        for v in variants:
            conservative, cubic = runs[v]
            if not conservative or not cubic:
                print(f"| {label} | {v} | not run |")
                continue
            c, q = conservative[k], cubic[k]
            first = first or c["answers"]
            passes = f"{c.get('device_given_up_pairs', 0):.0f} / {c.get('device_second_pass_pairs', 0):.0f} / {c.get('device_third_pass_pairs', 0):.0f}"
            print(f"| {label} | {v} | {c['ms']:.1f} | {q['ms']:.1f} | **{c['ms'] / q['ms']:.2f}** | {stage(c, 'narrow phase'):.1f} | "
                  f"{stage(c, 'host narrow phase'):.2f} | {passes} | {'same' if c['answers'] == first else 'differs'} |")
    print()


def gpu_public(folder, variants):
    print("OpenCL step, the public steps at δ = 0 (given as A B A B; the warm step B -> A -> B's last, as in")
    print("reports/opencl/scale/): ms per step")
    print("| step | build | conservative ms | cubic64 ms | conservative / cubic64 | narrow phase ms |")
    print("|---|---|---:|---:|---:|---:|")
    for scene in ["rod-twist", "cloth-funnel"]:
        for v in variants:
            conservative = steps(os.path.join(folder, f"fits-{scene}-conservative-{v}"))
            cubic = steps(os.path.join(folder, f"fits-{scene}-cubic64-{v}"))
            if not conservative or not cubic:
                continue
            c, q = conservative[2], cubic[2]
            print(f"| {scene} | {v} | {c['ms']:.2f} | {q['ms']:.2f} | {c['ms'] / q['ms']:.2f} | {stage(c, 'narrow phase'):.2f} |")
    print()


def scene_row(label, v, conservative, cubic):
    c = [r["ms"] for r in conservative]
    q = [r["ms"] for r in cubic]
    host = sum(stage(r, "host narrow phase") for r in conservative)
    given_up = sum(r.get("device_given_up_pairs", 0) for r in conservative)
    print(f"| {label} | {v} | {statistics.median(c):.3f} | {statistics.median(q):.3f} | **{statistics.median(c) / statistics.median(q):.2f}** | "
          f"{statistics.mean(c):.3f} | {statistics.mean(q):.3f} | **{statistics.mean(c) / statistics.mean(q):.2f}** | {host:.2f} | {given_up:.0f} |")


def gpu_paper(folder, variants):
    print("OpenCL step, the paper's spinning ball (99 steps at its δ): ms per step, median and mean over the steps; host")
    print("narrow phase ms and queries given up, summed over the steps")
    print("| scene | build | conservative median | cubic64 median | ratio | conservative mean | cubic64 mean | ratio | host narrow phase ms | given up |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for v in variants:
        conservative = steps(os.path.join(folder, f"ball-{v}-conservative"))
        cubic = steps(os.path.join(folder, f"ball-{v}-cubic64"))
        if conservative and cubic:
            scene_row("paper spinning ball", v, conservative, cubic)
    print()


def cpu(folder, variants):
    print("CPU step (all the machine's cores, `full` and `full+cubic64` in one process): ms per step, median and mean")
    print("over the scene's steps (one step each for the ball's steps 10 and 14)")
    print("| scene | build | conservative median | cubic64 median | ratio | conservative mean | cubic64 mean | ratio | host narrow phase ms | given up |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, label in [("cpu-step-10", "1M ball, step 10"), ("cpu-step-14", "1M ball, step 14"), ("cpu-paper-ball", "paper spinning ball")]:
        for v in variants:
            path = os.path.join(folder, f"{name}-{v}")
            conservative, cubic = steps(path, "full+conservative"), steps(path, "full+cubic64")
            if conservative and cubic:
                scene_row(label, v, conservative, cubic)
    print()


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    scale, step = sys.argv[1], sys.argv[2]
    variants = sys.argv[3:] or ["before", "after"]
    machine = os.path.join(scale, "machine.txt")
    if os.path.exists(machine):
        print("Machine and builds:\n\n```\n" + open(machine).read().strip() + "\n```\n")
    gpu_ball(scale, variants)
    gpu_paper(step, variants)
    gpu_public(scale, variants)
    cpu(scale, variants)


if __name__ == "__main__":
    main()
