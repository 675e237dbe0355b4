#!/usr/bin/python3
"""The attribution of apccd's gain in one run (reports/opencl/README.md): full, full:filter=on (apccd's separation
filter before the narrow phase), apccd:skip=off (sessions of one frame) and apccd, on the CPU and on the device.

Usage: attribution_table.py RESULTS.jsonl[.gz] DEVICE_LABEL THREADS
RESULTS is the run's --out results file; every finished cell's summary in it is read (a scene with cells missing
prints '-' there). Ratios are against full on the same backend, within this run.
"""
import gzip
import json
import sys

CELLS = ["full", "full:filter=on", "apccd:skip=off", "apccd"]


def cell_of(strategy):
    backend = "device" if ":backend=opencl" in strategy else "cpu"
    if strategy.startswith("full"):
        return ("full:filter=on" if ":filter=on" in strategy else "full"), backend
    if strategy.startswith("apccd"):
        return ("apccd:skip=off" if ":skip=off" in strategy else "apccd"), backend
    return None, backend


def main():
    results, device, threads = sys.argv[1:4]
    table = {}
    scenes = []
    for line in (gzip.open(results, "rt") if results.endswith(".gz") else open(results)):
        r = json.loads(line)
        if r.get("record") != "summary":
            continue
        cell, backend = cell_of(r["strategy"])
        if cell is None:
            continue
        if r["scene"] not in table:
            table[r["scene"]] = {}
            scenes.append(r["scene"])
        table[r["scene"]][(cell, backend)] = r["ms_per_step"]
    head = " | ".join(f"{c}, CPU {threads} thr" for c in CELLS) + " | " + " | ".join(f"{c}, {device}" for c in CELLS)
    print(f"| scene | {head} |")
    print("|" + "---|" * (1 + 2 * len(CELLS)))
    for scene in scenes:
        row = []
        for backend in ("cpu", "device"):
            base = table[scene].get(("full", backend))
            for c in CELLS:
                ms = table[scene].get((c, backend))
                if ms is None:
                    row.append("-")
                elif c == "full" or base is None:
                    row.append(f"{ms:.2f}")
                else:
                    row.append(f"{ms:.2f} ({base / ms:.2f}x)")
        print(f"| {scene} | " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
