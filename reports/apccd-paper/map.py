#!/usr/bin/python3
"""The map of where apccd's skipping pays, from scripts/apccd-map.sh's run (OUT/raw/map.json): map.md (for every
scene, resolution, narrow phase and backend, full / apccd at each steps_per_frame, with apccd's mean session length,
what skipping alone gives (apccd:skip=off / apccd) and why its sessions ended) and map.png (the same ratios at a
glance).

Usage: map.py OUT   (the folder holding raw/map.json)

A ratio is full's mean ms per step over apccd's (> 1: apccd is faster), both from the same invocation. A cell whose
steps have no colliding pair is flagged "no contact" and left out of the plot: a speed on a scene with nothing to
find is not a finding. Sessions: the mean length is steps / session starts; the reasons are the counters
session_end_* summed over the steps (strategies/apccd/session.hpp), the last session of a cell ending with the
run, uncounted."""
import json
import math
import os
import re
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

# What a session's skipped frame leaves out: apccd:skip=off's refit ("update", on the device also "boxes", "refit"
# and the host's share "update (host)") and full traversal. Everything else runs every step either way.
SKIPPABLE = ["update", "update (host)", "traversal", "boxes", "refit"]
REASONS = ["nf_max", "nf_adapted", "inflation_cap", "dangling", "pending", "skip_off"]
SCENES = ["spinning-ball", "drape", "flag", "twist", "funnel", "pile"]


def parse_scene(scene):
    m = re.match(r"(.+)-r(\d+)-spf(\d+)(\.json)?$", scene)
    return m.group(1), int(m.group(2)), int(m.group(3))


def kind(strategy):
    """(family, narrow phase, backend) of a resolved strategy name; apccd:skip=off is the family "noskip"."""
    family = strategy.split("+")[0]
    narrow = "cubic64" if strategy.startswith(family + "+cubic64") else "conservative"
    if family == "apccd" and ":skip=off" in strategy:
        family = "noskip"
    backend = "opencl" if "backend=opencl" in strategy else "cpu"
    return family, narrow, backend


def main(out):
    summaries = json.load(open(os.path.join(out, "raw", "map.json")))
    cells = {}
    for s in summaries:
        name, res, spf = parse_scene(s["scene"])
        family, narrow, backend = kind(s["strategy"])
        cells[(name, res, spf, narrow, backend, family)] = s
    keys = sorted({(n, r, narrow, b) for (n, r, spf, narrow, b, f) in cells}, key=lambda k: (SCENES.index(k[0]) if k[0] in SCENES else 99, k[1], k[2], k[3]))
    spfs = sorted({spf for (_, _, spf, _, _, _) in cells})
    rows, points, skip_points, reasons_rows, missed_rows = [], defaultdict(list), defaultdict(list), [], []
    no_contact = 0
    for name, res, narrow, backend in keys:
        row = f"| {name} | {res} | {narrow} | {backend} |"
        for spf in spfs:
            full = cells.get((name, res, spf, narrow, backend, "full"))
            apccd = cells.get((name, res, spf, narrow, backend, "apccd"))
            noskip = cells.get((name, res, spf, narrow, backend, "noskip"))
            if not full or not apccd:
                row += " - |"
                continue
            steps = apccd["steps"]
            starts = apccd["counters"].get("session_start", {}).get("mean", 1.0) * steps
            length = steps / starts if starts > 0 else float("inf")
            ratio = full["ms_per_step_mean"] / apccd["ms_per_step_mean"]
            for family, cell in (("full", full), ("apccd", apccd), ("apccd:skip=off", noskip)):
                if cell and cell.get("missed", 0) > 0:
                    missed_rows.append(f"| {name} r{res} spf{spf} | {narrow} | {backend} | {family} | {cell['missed']} of {cell['colliding']} |")
            if not cell_has_contact(full) or not cell_has_contact(apccd):
                no_contact += 1
                row += f" no contact ({ratio:.2f}x) |"
                continue
            bold = "**" if ratio >= 1 else ""
            skipping = noskip["ms_per_step_mean"] / apccd["ms_per_step_mean"] if noskip else float("nan")
            row += f" {bold}{ratio:.2f}x{bold} ({length:.1f}; {skipping:.2f}x) |"
            points[(narrow, backend)].append((name, res, spf, ratio, length))
            if noskip:
                skippable = sum(noskip["stage_ms_mean"].get(stage, 0.0) for stage in SKIPPABLE)
                rest = noskip["ms_per_step_mean"] - skippable
                bound = noskip["ms_per_step_mean"] / rest if rest > 0 else float("inf")
                skip_points[(narrow, backend)].append((name, res, spf, skipping, length, bound))
            ended = {r: apccd["counters"].get("session_end_" + r, {}).get("mean", 0.0) * steps for r in REASONS}
            total = sum(ended.values())
            if total > 0:
                shares = ", ".join(f"{r} {100 * v / total:.0f}%" for r, v in ended.items() if v > 0)
                reasons_rows.append(f"| {name} r{res} spf{spf} | {narrow} | {backend} | {steps} | {starts:.0f} | {length:.1f} | {shares} |")
        rows.append(row)
    best = max((p for ps in points.values() for p in ps), key=lambda p: p[3], default=None)
    with open(os.path.join(out, "map.md"), "w") as md:
        md.write("# Where apccd's skipping pays: full / apccd\n\n")
        md.write(open(os.path.join(out, "raw", "command.txt")).read().replace("# ", "    # ").replace("\nccdbench", "\n    ccdbench") + "\n")
        run = dict(line.rstrip("\n").split("\t") for line in open(os.path.join(out, "raw", "run.tsv")))
        machine = summaries[0].get("machine", "?") if summaries else "?"
        md.write(f"Machine: {machine}, {summaries[0].get('threads', '?') if summaries else '?'} threads; "
                 f"profile {run.get('profile')}, {run.get('elapsed_s')} s of runs. Each cell: mean ms per step of full over "
                 "apccd with the same narrow phase and backend (> 1: apccd faster, in bold); in parentheses apccd's mean "
                 "session length in frames and what skipping alone gives: apccd:skip=off's mean ms over apccd's (the same "
                 "front end, every step a session start). Every cell verified against the exact truth.\n\n")
        if best:
            md.write(f"Best cell: {best[0]} r{best[1]} spf{best[2]}: {best[3]:.2f}x (sessions of {best[4]:.1f} frames). "
                     f"Cells where apccd is faster: {sum(1 for ps in points.values() for p in ps if p[3] >= 1)} of "
                     f"{sum(len(ps) for ps in points.values())} with contact; {no_contact} cells without a colliding pair.\n\n")
        md.write("At a glance, the median over the scenes and resolutions with contact of: full / apccd; apccd:skip=off / "
                 "apccd (skipping's own share); the most skipping could give, were every skipped frame free "
                 "(apccd:skip=off's ms over its ms less its refit and traversal stages); and the sessions' mean length:\n\n")
        md.write("| narrow phase, backend | " + " | ".join(f"spf {s}" for s in spfs) + " |\n|---|" + "---|" * len(spfs) + "\n")
        for panel in sorted(points):
            cells_of = lambda spf, series: [p for p in series.get(panel, []) if p[2] == spf]
            entries = []
            for spf in spfs:
                ratios = [p[3] for p in cells_of(spf, points)]
                skips = [p[3] for p in cells_of(spf, skip_points)]
                bounds = [p[5] for p in cells_of(spf, skip_points)]
                lengths = [p[4] for p in cells_of(spf, points)]
                entries.append(f"{median(ratios):.2f}x; {median(skips):.2f}x; at most {median(bounds):.2f}x; {median(lengths):.1f} frames"
                               if ratios else "-")
            md.write(f"| {panel[0]}, {panel[1]} | " + " | ".join(entries) + " |\n")
        ended_all = defaultdict(float)
        for key, cell in cells.items():
            if key[5] == "apccd":
                for r in REASONS:
                    ended_all[r] += cell["counters"].get("session_end_" + r, {}).get("mean", 0.0) * cell["steps"]
        total = sum(ended_all.values())
        if total > 0:
            md.write("\nSessions ended, over every apccd cell: " +
                     ", ".join(f"{r} {100 * v / total:.0f}%" for r, v in sorted(ended_all.items(), key=lambda kv: -kv[1]) if v > 0) +
                     f" (of {total:.0f}). nf_max, nf_adapted and dangling are the paper's rules; inflation_cap and pending are "
                     "ours (strategies/apccd/session.hpp).\n\n")
        md.write("| scene | resolution | narrow phase | backend | " + " | ".join(f"spf {s}" for s in spfs) + " |\n")
        md.write("|---|---:|---|---|" + "---:|" * len(spfs) + "\n")
        md.write("\n".join(rows) + "\n\n")
        md.write("## Why apccd's sessions ended\n\n| cell | narrow phase | backend | steps | sessions | mean length | ended by |\n"
                 "|---|---|---|---:|---:|---:|---|\n")
        md.write("\n".join(reasons_rows) + "\n\n")
        md.write("## Missed collisions\n\n")
        if missed_rows:
            md.write("| cell | narrow phase | backend | strategy | missed |\n|---|---|---|---|---|\n" + "\n".join(missed_rows) + "\n")
        else:
            md.write("None in any cell.\n")
    plot(points, skip_points, spfs, os.path.join(out, "map.png"))


def median(values):
    values = sorted(values)
    if not values:
        return float("nan")
    middle = len(values) // 2
    return values[middle] if len(values) % 2 else (values[middle - 1] + values[middle]) / 2


def cell_has_contact(cell):
    return cell.get("colliding", 0) > 0


def plot(points, skip_points, spfs, path):
    panels = sorted(points)
    if not panels:
        return
    fig, axes = plt.subplots(2, len(panels), figsize=(5.5 * len(panels), 8), squeeze=False, sharey="row", sharex=True)
    for column, panel in enumerate(panels):
        for row, (series, ylabel) in enumerate(((points, "full / apccd (above 1: apccd faster)"),
                                                (skip_points, "apccd:skip=off / apccd (skipping alone)"))):
            ax = axes[row][column]
            by_line = defaultdict(list)
            for name, res, spf, ratio, *_ in series.get(panel, []):
                by_line[(name, res)].append((spf, ratio))
            labelled = set()
            for (name, res), pts in sorted(by_line.items()):
                pts.sort()
                ranks = sorted(r for (n, r) in by_line if n == name)
                color = f"C{SCENES.index(name) if name in SCENES else 9}"
                marker = ["o", "s", "D", "^"][min(3, ranks.index(res))]
                ax.plot([p[0] for p in pts], [p[1] for p in pts], marker=marker, color=color, alpha=0.8,
                        label=name if name not in labelled else None)
                labelled.add(name)
            ax.axhline(1.0, color="black", linewidth=0.8)
            ax.set_xscale("log", base=2)
            ax.set_yscale("log", base=2)
            ax.set_xticks(spfs)
            ax.set_xticklabels([str(s) for s in spfs])
            ticks = [0.5, 0.71, 1, 1.41, 2, 2.83]
            ax.set_yticks(ticks)
            ax.set_yticklabels([str(t) for t in ticks])
            ax.grid(True, which="both", alpha=0.3)
            if row == 0:
                ax.set_title(f"{panel[0]}, {panel[1]}")
            if row == 1:
                ax.set_xlabel("CCD steps per simulated frame (less motion per step to the right)")
            if column == 0:
                ax.set_ylabel(ylabel)
    axes[0][-1].legend(fontsize=7, loc="best", title="scene (o, s, D: smallest to largest resolution)", title_fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
