#!/usr/bin/python3
"""apccd and full on both backends, one table per run (reports/opencl/README.md, "apccd on the device").

Usage: apccd_table.py SUMMARY.json RESULTS.jsonl[.gz] DEVICE_LABEL THREADS
SUMMARY.json is a `ccdbench run --json` array of one run with the cells full, apccd, full:backend=opencl and
apccd:backend=opencl (conservative); RESULTS.jsonl is that run's --out results file (a folder of its own: its step
records carry no δ; the last `steps` records of a cell are read), for apccd's per-step counters (session starts,
nf, pending pairs). Ratios are within this run only.
"""
import gzip
import json
import sys
from collections import defaultdict


def kind(strategy):
    name = "apccd" if strategy.startswith("apccd") else "full" if strategy.startswith("full") else None
    if name is None or "+conservative" not in strategy:
        return None
    return name + (" device" if ":backend=opencl" in strategy else " cpu")


def main():
    summary_file, results_file, device, threads = sys.argv[1:5]
    cells = {}
    order = []
    for s in json.load(open(summary_file)):
        k = kind(s["strategy"])
        if k is None:
            continue
        key = (s["scene"], s["thickness"])
        if key not in cells:
            cells[key] = {}
            order.append(key)
        cells[key][k] = s
    steps = defaultdict(list)
    for line in (gzip.open(results_file, "rt") if results_file.endswith(".gz") else open(results_file)):
        r = json.loads(line)
        if r.get("record") != "step" or not r.get("strategy", "").startswith("apccd") or ":backend=opencl" not in r["strategy"]:
            continue
        steps[(r["scene"], r["strategy"])].append(r)
    print(f"| scene | steps | full, CPU {threads} thr | apccd, CPU {threads} thr | full, {device} | apccd, {device} | "
          f"apccd vs full: CPU / {device} | apccd: {device} vs CPU | session starts | mean nf | mean pending pairs | "
          f"colliding | missed apccd CPU / {device} | false alarms CPU / {device} | apccd {device} stages (ms, >= 0.05) |")
    print("|" + "---|" * 15)
    for key in order:
        c = cells[key]
        if len(c) < 4:
            continue
        ms = {k: v["ms_per_step"] for k, v in c.items()}
        dev = c["apccd device"]
        records = steps[(key[0], dev["strategy"])][-dev["steps"]:]
        starts = sum(1 for r in records if r.get("session_start", 0) == 1)
        nf = sum(r.get("nf", 0) for r in records) / max(len(records), 1)
        pending = sum(r.get("pending_pairs", 0) for r in records) / max(len(records), 1)
        stages = ", ".join(f"{name} {value:.2f}" for name, value in sorted(dev.get("stage_ms", {}).items()) if value >= 0.05)
        verified = dev.get("verified", False)
        missed = f"{c['apccd cpu'].get('missed', '-')} / {dev.get('missed', '-')}" if verified else "not verified"
        alarms = f"{c['apccd cpu'].get('false_alarms', '-')} / {dev.get('false_alarms', '-')}" if verified else "-"
        colliding = dev.get("colliding", "-") if verified else f"{dev.get('reported', '-')} reported"
        print(f"| {key[0]} (δ = {key[1]:.3g}) | {dev['steps']} | {ms['full cpu']:.2f} | {ms['apccd cpu']:.2f} | {ms['full device']:.2f} | "
              f"**{ms['apccd device']:.2f}** | {ms['full cpu'] / ms['apccd cpu']:.2f}x / {ms['full device'] / ms['apccd device']:.2f}x | "
              f"{ms['apccd cpu'] / ms['apccd device']:.2f}x | {starts} of {len(records)} | {nf:.2f} | {pending:.0f} | {colliding} | {missed} | "
              f"{alarms} | {stages} |")


if __name__ == "__main__":
    main()
