#!/usr/bin/env python3
"""Tables of reports/opencl/scale/README.md from scripts/device-opencl-scale.sh's folder (NAME.json, NAME.jsonl.gz,
NAME.smi, NAME.failed): the driver's memory for a context; where a step fits, the chunked path's ms per step (after)
over the whole-step path's (before), step by step; and frames 26-28 of the 1M-triangle spinning ball under each
memory budget: ms per step, chunks, our count of device buffers, the driver's peak for the process, and whether
each step's answers digest equals the CPU `full`'s. Exits 1 on a digest that differs, a run that failed, or a
driver peak above the budget plus the context's. Usage: table.py FOLDER"""

import gzip
import json
import os
import sys

MIB = 1024.0 * 1024.0
BUDGETS = {"2G": 2 << 30, "4G": 4 << 30, "8G": 8 << 30}
# The ball's steps the issue names (frames 2..15 were generated: step k of the run is frame 2 + k -> 3 + k).
BALL_STEPS = {2: 0, 10: 8, 14: 12}


def load(folder, name):
    stem = os.path.join(folder, name)
    if os.path.exists(stem + ".failed"):
        return {"failed": open(stem + ".failed").read().strip(), "err": open(stem + ".err").read().strip().splitlines()[-1:]}
    if not os.path.exists(stem + ".json"):
        return None
    steps = []
    with gzip.open(stem + ".jsonl.gz", "rt") as lines:
        for line in lines:
            record = json.loads(line)
            if record.get("record") == "step":
                steps.append(record)
    steps.sort(key=lambda r: r["step"])
    smi = open(stem + ".smi").read().strip() if os.path.exists(stem + ".smi") else ""
    return {"summaries": json.load(open(stem + ".json")), "steps": steps, "driver_mib": float(smi) if smi else None}


def main():
    folder = sys.argv[1]
    problems = []
    context = load(folder, "context")
    context_mib = context["driver_mib"] if context and "failed" not in context else None
    print(f"Context: the driver's peak for the ci suite's first 2 steps under the default budget: {context_mib} MiB "
          "(a context, its kernels and a few MiB of buffers); a budget's peak may pass it by this much.\n")

    variants = [v for v in ["before", "chunk", "after"] if os.path.exists(os.path.join(folder, f"fits-rod-twist-conservative-{v}.json"))]
    if variants:
        print("Where the whole step fits: ms per step of each build (before: the whole-step path), same warm machine")
        print("| step | narrow phase | " + " | ".join(f"{v} ms" for v in variants) + " | " +
              " | ".join(f"{v} / before" for v in variants[1:]) + " | chunks | digests equal |")
        print("|---|---|" + "---:|" * (2 * len(variants) - 1) + "---:|---|")
        for narrow in ["conservative", "cubic64"]:
            for scene in ["rod-twist", "cloth-funnel", "ball"]:
                runs = [load(folder, f"fits-{scene}-{narrow}-{v}") for v in variants]
                if any(r is None or "failed" in r for r in runs):
                    print(f"| {scene} | {narrow} | " + " | ".join(str(r and r.get("failed")) for r in runs) + " |")
                    continue
                picks = BALL_STEPS.items() if scene == "ball" else [(scene + " (warm)", 2)]
                for label, k in picks:
                    steps = [r["steps"][k] for r in runs]
                    same = all(step.get("answers") == steps[0].get("answers") for step in steps)
                    if not same:
                        problems.append(f"fits {scene} {narrow} step {label}: digests differ")
                    name = f"ball step {label}" if scene == "ball" else label
                    print(f"| {name} | {narrow} | " + " | ".join(f"{step['ms']:.1f}" for step in steps) + " | " +
                          " | ".join(f"{step['ms'] / steps[0]['ms']:.3f}" for step in steps[1:]) +
                          f" | {steps[-1].get('device_chunks', 0):.0f} | {'yes' if same else 'NO'} |")
        print()

    limits = sorted(int(n[len("limits-"):-len(".json")]) for n in os.listdir(folder)
                    if n.startswith("limits-") and n.endswith(".json") and n[len("limits-"):-len(".json")].isdigit())
    cubic = load(folder, "limits-cubic64")
    if limits and cubic and "failed" not in cubic:
        print("The first device pass's iterations (device_iterations=) on the ball's resting steps, conservative at the scene's δ:")
        print("ms per step (narrow phase ms; queries given up / in the third pass / on the host), and over cubic64's")
        print("| limit | " + " | ".join(f"step {label}" for label in BALL_STEPS) + " | " + " | ".join(f"step {label} / cubic64" for label in BALL_STEPS) +
              " | digests equal |")
        print("|---:|" + "---:|" * (2 * len(BALL_STEPS)) + "---|")
        reference = None
        for limit in limits:
            run = load(folder, f"limits-{limit}")
            if run is None or "failed" in run:
                print(f"| {limit} | failed |")
                continue
            digests = [s.get("answers") for s in run["steps"]]
            reference = reference or digests
            cells, ratios = [], []
            for label, k in BALL_STEPS.items():
                step = run["steps"][k]
                passes = (f", passes 2 and 3: {step['device_second_pass_ms']:.0f} + {step['device_third_pass_ms']:.0f} ms"
                          if "device_third_pass_ms" in step else "")
                cells.append(f"{step['ms']:.0f} ({step['stages'].get('narrow phase', 0):.0f}{passes}; {step.get('device_given_up_pairs', 0):.0f}/"
                             f"{step.get('device_third_pass_pairs', 0):.0f}/{step.get('host_decided_pairs', 0):.0f})")
                ratios.append(f"{step['ms'] / cubic['steps'][k]['ms']:.2f}")
            same = digests == reference
            if not same:
                problems.append(f"limits {limit}: digests differ from limit {limits[0]}'s")
            print(f"| {limit} | " + " | ".join(cells) + " | " + " | ".join(ratios) + f" | {'yes' if same else 'NO'} |")
        print("| cubic64 | " + " | ".join(f"{cubic['steps'][k]['ms']:.0f} ({cubic['steps'][k]['stages'].get('narrow phase', 0):.0f})"
                                          for k in BALL_STEPS.values()) + " |" + " |" * len(BALL_STEPS) + " |")
        print()

    print("Frames 26-28 (2 steps past the old 2^32 ceiling) under a memory budget; digests against the CPU `full`'s")
    print("| δ | narrow phase | budget | step | ms | candidates | tests | chunks | our buffers MiB | driver peak MiB | "
          "budget + context MiB | digest = CPU's |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for thickness in ["0", "scene"]:
        for narrow in ["conservative", "cubic64"]:
            cpu = load(folder, f"scale-{thickness}-{narrow}-cpu")
            cpu_digests = [s.get("answers") for s in cpu["steps"]] if cpu and "failed" not in cpu else None
            for budget, limit in BUDGETS.items():
                run = load(folder, f"scale-{thickness}-{narrow}-{budget}")
                if run is None:
                    print(f"| {thickness} | {narrow} | {budget} | not run | | | | | | | | |")
                    continue
                if "failed" in run:
                    problems.append(f"scale {thickness} {narrow} {budget}: failed {run['failed']} {run['err']}")
                    print(f"| {thickness} | {narrow} | {budget} | failed: {run['err']} | | | | | | | | |")
                    continue
                allowed = limit / MIB + (context_mib or 0)
                if run["driver_mib"] is not None and run["driver_mib"] > allowed:
                    problems.append(f"scale {thickness} {narrow} {budget}: driver peak {run['driver_mib']} MiB > {allowed:.0f}")
                for k, step in enumerate(run["steps"]):
                    if cpu_digests is None:
                        agrees = "no CPU run"
                        problems.append(f"scale {thickness} {narrow}: no CPU digests")
                    else:
                        agrees = "yes" if step.get("answers") == cpu_digests[k] else "NO"
                        if agrees == "NO":
                            problems.append(f"scale {thickness} {narrow} {budget} step {k}: digest differs from the CPU's")
                    print(f"| {thickness} | {narrow} | {budget} | {26 + k} | {step['ms']:.0f} | {step['candidate_pairs']} | "
                          f"{step['elementary_tests']} | {step.get('device_chunks', 0):.0f} | {step['device_bytes'] / MIB:.0f} | "
                          f"{run['driver_mib']:.0f} | {allowed:.0f} | {agrees} |")
    if cpu_digests is not None:
        print()
    if problems:
        print("\nproblems:\n  " + "\n  ".join(problems))
        sys.exit(1)
    print("\nevery digest equals the CPU's and every peak is within its budget plus the context")


if __name__ == "__main__":
    main()
