#!/usr/bin/env python3
"""The narrow phase's step tables (README.md here) from scripts/device-narrowphase.sh's JSON summaries: for each
scene, `full` (conservative) and `full+cubic64` on the CPU (every core) and on the GPU (OpenCL), before -> after:
ms per step (median), the narrow phase's stage and the host's share of it (queries handed back by the device), and
conservative / cubic64 on the same backend. Usage: table.py FOLDER (the unpacked narrowphase-device.tgz)."""

import json
import os
import sys


def summaries(folder, part, variant):
    path = os.path.join(folder, f"{part}-{variant}.json")
    return json.load(open(path)) if os.path.exists(path) else []


def key(summary):
    strategy = summary["strategy"]
    narrow = "conservative" if strategy.startswith("full+conservative") else "cubic64"
    backend = "GPU" if "backend=opencl" in strategy else "CPU"
    return summary["scene"], backend, narrow


def main(folder):
    print("| scene | triangles | tests/step | backend | conservative ms/step | cubic64 ms/step | conservative / cubic64 "
          "| conservative narrow phase ms | of it on the host (ms) |")
    print("|---|---:|---:|---|---:|---:|---:|---:|---:|")
    for part in ("rod-twist", "cloth-funnel", "paper", "large"):
        rows = {v: {key(s): s for s in summaries(folder, part, v)} for v in ("before", "after")}
        scenes = []
        for scene, _, _ in rows["after"]:
            if scene not in scenes:
                scenes.append(scene)
        for scene in scenes:
            for backend in ("CPU", "GPU"):
                cells = {}
                for v in ("before", "after"):
                    c = rows[v].get((scene, backend, "conservative"))
                    q = rows[v].get((scene, backend, "cubic64"))
                    if c and q:
                        cells[v] = (c, q)
                if len(cells) < 2:
                    continue
                (cb, qb), (ca, qa) = cells["before"], cells["after"]
                host = lambda s: s["stage_ms"].get("host narrow phase", 0.0)
                name = {"rod-twist": "rod-twist 3036", "cloth-funnel": "cloth-funnel 227"}.get(part, scene)
                print(f"| {name} | {ca['triangles']:,} | {ca['elementary_tests']:,.0f} | {backend} "
                      f"| {cb['ms_per_step']:.2f} → **{ca['ms_per_step']:.2f}** | {qb['ms_per_step']:.2f} → {qa['ms_per_step']:.2f} "
                      f"| {cb['ms_per_step'] / qb['ms_per_step']:.2f} → **{ca['ms_per_step'] / qa['ms_per_step']:.2f}** "
                      f"| {cb['stage_ms'].get('narrow phase', 0):.2f} → {ca['stage_ms'].get('narrow phase', 0):.2f} "
                      f"| {host(cb):.2f} → {host(ca):.2f} |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
