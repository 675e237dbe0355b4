#!/usr/bin/python3
"""Prints the tables of reports/cpu-step/README.md from the raw runs in reports/cpu-step/device/ (what
scripts/device-cpu-step.sh wrote on the GPU machine). Usage: /usr/bin/python3 reports/cpu-step/tables.py"""

import gzip
import json
import pathlib

here = pathlib.Path(__file__).resolve().parent
run1 = here / "device" / "run1"
run2 = here / "device" / "run2"
VARIANTS = ["before", "traversal", "scaling", "multiversion", "boxes"]


def summaries(path):
    return json.loads(path.read_text())


def one(path):
    (s,) = summaries(path)
    return s


def stage(s, name):
    return s["stage_ms"].get(name, 0.0)


def fmt(x):
    return f"{x:.1f}" if x < 1000 else f"{x:.0f}"


def machine_ceiling():
    data = json.loads((run1 / "machine_benchmark.json").read_text())
    rows = {}
    for b in data["benchmarks"]:
        name, threads = b["name"].split("/")[0], int(b["name"].split("threads:")[1].split("/")[0])
        rows.setdefault(name, {})[threads] = b["real_time"]
    print("| kernel | " + " | ".join(f"{t} threads" for t in sorted(rows["BM_ComputeBound"])) + " |")
    print("|---|" + "---|" * len(rows["BM_ComputeBound"]))
    for name, times in rows.items():
        one_thread = times[1]
        print(f"| {name} | " + " | ".join(f"{one_thread / times[t]:.2f}x" for t in sorted(times)) + " |")


def broad_phase():
    data = json.loads((run1 / "bvh_benchmark.json").read_text())
    rows = {}
    for b in data["benchmarks"]:
        parts = b["name"].split("/")
        if parts[0] != "BM_SelfTraversal":
            continue
        design, step, threads = parts[1], parts[2], int(parts[3].split(":")[1])
        rows.setdefault((step, design), {})[threads] = b["real_time"]
    threads = sorted(next(iter(rows.values())))
    print("| step | design | " + " | ".join(f"{t} thr (ms)" for t in threads) + " |")
    print("|---|---|" + "---|" * len(threads))
    for (step, design), times in sorted(rows.items()):
        print(f"| {step} | {design} | " + " | ".join(fmt(times[t]) for t in threads) + " |")


def public_variants():
    # multiversion is the final code for default full (boxes was reverted; the filter's flatten does not run here).
    print("| step | threads | " + " | ".join(VARIANTS) + " | before / multiversion |")
    print("|---|---|" + "---|" * (len(VARIANTS) + 1))
    for step in ["rod-twist", "cloth-funnel"]:
        for t in [1, 2, 16]:
            cells = [one(run1 / f"public-{step}-{v}-{t}.json") for v in VARIANTS]
            text = [f"{fmt(s['ms_per_step'])} ({fmt(stage(s, 'traversal'))} + {fmt(stage(s, 'narrow phase'))})" for s in cells]
            ratio = cells[0]["ms_per_step"] / cells[VARIANTS.index("multiversion")]["ms_per_step"]
            print(f"| {step} | {t} | " + " | ".join(text) + f" | {ratio:.2f}x |")


def scaling():
    print("| step | strategy | build | " + " | ".join(f"{t} thr" for t in [1, 2, 4, 8, 16]) + " | 16 vs 1 |")
    print("|---|---|---|" + "---|" * 6)
    for step in ["rod-twist", "cloth-funnel"]:
        for index, label in enumerate(["full", "full:filter=on", "full+cubic64"]):
            for v in ["before", "boxes"]:
                times = [summaries(run1 / f"scaling-{step}-{v}-{t}.json")[index]["ms_per_step"] for t in [1, 2, 4, 8, 16]]
                print(f"| {step} | {label} | {v} | " + " | ".join(fmt(x) for x in times) + f" | {times[0] / times[-1]:.1f}x |")


def filter_variants():
    print("| build | 1 thread (ms) | 16 threads (ms) |")
    print("|---|---|---|")
    for v in ["boxes", "fclones", "fflat"]:
        a, b = one(run2 / f"filter-rod-twist-{v}-1.json"), one(run2 / f"filter-rod-twist-{v}-16.json")
        print(f"| {v} | {fmt(a['ms_per_step'])} (narrow {fmt(stage(a, 'narrow phase'))}) | {fmt(b['ms_per_step'])} (narrow {fmt(stage(b, 'narrow phase'))}) |")


def digests(path):
    out = {}
    with gzip.open(path, "rt") as lines:
        for line in lines:
            record = json.loads(line)
            if record["record"] == "step":
                out[(record["scene"], record["step"])] = (record["answers"], record["candidate_pairs"], record["elementary_tests"])
    return out


def paper():
    print("| run | scene | before ms/step (traversal + narrow) | after | before / after |")
    print("|---|---|---|---|---|")
    for name in ["16-delta", "16-zero", "2-delta", "1-delta"]:
        before, after = summaries(run2 / f"paper-before-{name}.json"), summaries(run2 / f"paper-boxes-{name}.json")
        for x, y in zip(before, after):
            text = [f"{fmt(s['ms_per_step'])} ({fmt(stage(s, 'traversal'))} + {fmt(stage(s, 'narrow phase'))})" for s in (x, y)]
            print(f"| {name} | {x['scene']} | {text[0]} | {text[1]} | {x['ms_per_step'] / y['ms_per_step']:.2f}x |")
    print()
    for name in ["16-delta", "16-zero", "2-delta", "1-delta"]:
        a, b = digests(run2 / f"paper-before-{name}.jsonl.gz"), digests(run2 / f"paper-boxes-{name}.jsonl.gz")
        same = sum(1 for key in a if b.get(key) == a[key])
        print(f"- {name}: {len(a)} steps, {same} with the same answers digest, candidates and tests in both builds")


for title, table in [("machine ceiling (run 1)", machine_ceiling), ("broad phase designs (run 1)", broad_phase),
                     ("public steps, every build (run 1)", public_variants), ("thread scaling (run 1)", scaling),
                     ("full:filter=on on rod-twist (run 2)", filter_variants), ("paper suite (run 2)", paper)]:
    print(f"### {title}\n")
    table()
    print()
