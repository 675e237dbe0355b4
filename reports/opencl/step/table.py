#!/usr/bin/env python3
"""Tables of reports/opencl/step/README.md from scripts/device-opencl-step.sh's files (NAME-VARIANT-NARROW.json,
.jsonl.gz, .smi): for each step or scene and narrow phase, each variant's ms per step (the harness's median over
steps of each step's median over passes; on the public steps, given as A B A B, that is a warm step), the first step
of the first pass (cold: the lists grow), every stage, the device's idle time between commands, the time in no
stage, our count of device buffers and the driver's peak for the process (nvidia-smi), and whether every step's
answers digest equals the first variant's. Usage: table.py FOLDER [VARIANT ...] (default: every variant found,
`before` first and `after` last)."""

import gzip
import json
import os
import sys

STAGES = ["upload", "boxes", "refit", "traversal", "expansion", "narrow phase", "download", "host narrow phase", "output",
          "launch and wait"]
PARTS = ["tiny", "rod-twist", "cloth-funnel", "ci", "default", "paper", "large"]


def load(folder, part, variant, narrow):
    stem = os.path.join(folder, f"{part}-{variant}-{narrow}")
    if not os.path.exists(stem + ".json"):
        return None
    summaries = json.load(open(stem + ".json"))
    steps = []
    with gzip.open(stem + ".jsonl.gz", "rt") as lines:
        for line in lines:
            record = json.loads(line)
            if record.get("record") == "step":
                steps.append(record)
    smi = open(stem + ".smi").read().strip() if os.path.exists(stem + ".smi") else ""
    return {"summaries": summaries, "steps": steps, "driver_mib": float(smi) if smi else None}


def variants_in(folder):
    found = set()
    for name in os.listdir(folder):
        if name.endswith(".json") and name.count("-") >= 2:
            stem = name[:-5]
            for part in PARTS:
                if stem.startswith(part + "-"):
                    found.add(stem[len(part) + 1:].rsplit("-", 1)[0])
    ordered = sorted(found - {"before", "after"})
    return (["before"] if "before" in found else []) + ordered + (["after"] if "after" in found else [])


def digests(run):
    return [(s["scene"], s["step"], s["answers"]) for s in run["steps"]]


def main(folder, variants):
    variants = variants or variants_in(folder)
    print("| step(s) | narrow phase | variant | ms/step | cold first step | " + " | ".join(STAGES) +
          " | device idle | in no stage | device MiB: ours / driver | answers |")
    print("|---|---|---|---:|---:|" + "---:|" * len(STAGES) + "---:|---:|---|---|")
    for part in PARTS:
        for narrow in ("cubic64", "conservative"):
            runs = {v: load(folder, part, v, narrow) for v in variants}
            runs = {v: r for v, r in runs.items() if r}
            if not runs:
                continue
            reference = digests(next(iter(runs.values())))
            for variant, run in runs.items():
                summaries = run["summaries"]
                # One row per part: the mean over the part's scenes of each scene's figures (one scene but in the suites).
                n = len(summaries)
                mean = lambda f: sum(f(s) for s in summaries) / n
                ms = mean(lambda s: s["ms_per_step"])
                cold = sum(s["ms"] for s in run["steps"] if s["step"] == 0) / max(1, sum(1 for s in run["steps"] if s["step"] == 0))
                stages = [mean(lambda s, st=st: s["stage_ms"].get(st, 0.0)) for st in STAGES]
                idle = mean(lambda s: s["counters"].get("device_idle_ms", {}).get("mean", float("nan")))
                unattributed = mean(lambda s: s["unattributed_ms_mean"])
                ours = max(s["device_bytes"] for s in summaries) / 2**20
                driver = run["driver_mib"]
                same = "same" if digests(run) == reference else "**differ**"
                label = {"rod-twist": "rod-twist 3036", "cloth-funnel": "cloth-funnel 227", "large": "large (1M triangles, 3 steps)",
                         "paper": "paper suite, mean of scenes", "ci": "ci suite, mean of scenes", "default": "default suite, mean of scenes",
                         "tiny": "ci suite, 2 steps"}[part]
                bold = "**" if variant == "after" else ""
                print(f"| {label} | {narrow} | {variant} | {bold}{ms:.2f}{bold} | {cold:.2f} | " + " | ".join(f"{x:.2f}" for x in stages) +
                      f" | {idle:.2f} | {unattributed:.3f} | {ours:.0f} / {driver:.0f} | {same} |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
