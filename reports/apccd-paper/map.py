#!/usr/bin/python3
"""The map of where apccd's skipping pays, from scripts/apccd-map.sh's run (OUT/raw/map.json): map.md (for every
scene, resolution, narrow phase and backend, full / apccd at each steps_per_frame, with apccd's mean session length,
what skipping alone gives (apccd:skip=off / apccd) and why its sessions ended; where each one's time goes, stage by
stage) and map.png (the same ratios at a glance).

Usage: map.py OUT [--parity CPU_MAP]   (OUT: the folder holding raw/map.json)

--parity verifies the cells that ran without the exact truth (an OpenCL map run with VERIFY=none, to spare a GPU
machine's time) by their answers: a cell whose every step's digest (OUT/raw/answers.tsv.gz, from answers.py) equals
that of the same strategy's verified CPU cell in CPU_MAP reported the same pairs and TOIs, so it has that cell's
verdicts (colliding, missed, false alarms); a cell whose digests differ anywhere stays unverified and says so.

A ratio is full's mean ms per step over apccd's (> 1: apccd is faster), both from the same invocation. A cell whose
steps have no colliding pair is flagged "no contact" and left out of the plot and the medians: a speed on a scene with
nothing to find is not a finding; so is a cell that was not verified against the exact truth ("unverified"). With
cubic64, apccd is mapped twice: with the paper's front end (the box filter, then the distance heuristic) and with the
box filter alone (heuristic=boxes, the cheaper front end in front of cubic64). Sessions: the mean length is steps /
session starts; the reasons are the counters session_end_* summed over the steps (strategies/apccd/session.hpp), the
last session of a cell ending with the run, uncounted."""
import gzip
import json
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
# The apccd families a panel compares with full: the paper's front end, and with cubic64 the box filter alone.
FAMILY_LABEL = {"apccd": "", "boxes": " (heuristic=boxes)"}
# A stage is named in the stage tables when it takes at least this share of its strategy's summed step.
STAGE_SHARE_SHOWN = 0.08


def parse_scene(scene):
    m = re.match(r"(.+)-r(\d+)-spf(\d+)(\.json)?$", scene)
    return m.group(1), int(m.group(2)), int(m.group(3))


def kind(strategy):
    """(family, narrow phase, backend) of a resolved strategy name: full, apccd, noskip (apccd:skip=off) or boxes
    (apccd:heuristic=boxes)."""
    family = strategy.split("+")[0]
    narrow = "cubic64" if strategy.startswith(family + "+cubic64") else "conservative"
    if family == "apccd" and ":skip=off" in strategy:
        family = "noskip"
    elif family == "apccd" and ":heuristic=boxes" in strategy:
        family = "boxes"
    backend = "opencl" if "backend=opencl" in strategy else "cpu"
    return family, narrow, backend


def panel_name(panel):
    narrow, backend, family = panel
    return f"{narrow}{FAMILY_LABEL[family]}, {backend}"


def read_answers(folder):
    """cell -> (scene content digest, δ, {step: digest}) from FOLDER/raw/answers.tsv.gz (answers.py)."""
    answers = {}
    with gzip.open(os.path.join(folder, "raw", "answers.tsv.gz"), "rt") as tsv:
        next(tsv)
        for line in tsv:
            cell, content, thickness, step, digest = line.rstrip("\n").split("\t")
            answers.setdefault(cell, (content, thickness, {}))[2][int(step)] = digest
    return answers


def verify_by_parity(summaries, out, cpu_map):
    """Gives each unverified OpenCL cell the verdicts of the verified CPU cell of the same scene and strategy when both
    ran the same scene content at the same δ and every step's answers digest agrees (see the usage); returns (cells
    verified so, cells whose answers differ or cannot be compared)."""
    mine, theirs = read_answers(out), read_answers(cpu_map)
    cpu = {}
    for c in json.load(open(os.path.join(cpu_map, "raw", "map.json"))):
        family, narrow, backend = kind(c["strategy"])
        if backend == "cpu" and c.get("verified"):
            cpu[(c["scene"], family, narrow)] = c
    agreed = differed = 0
    for cell in summaries:
        family, narrow, backend = kind(cell["strategy"])
        reference = cpu.get((cell["scene"], family, narrow))
        if cell.get("verified") or backend != "opencl" or reference is None:
            continue
        content, thickness, steps = mine.get(cell["cell"], (None, None, {}))
        expected = theirs.get(reference["cell"], (None, None, {}))
        if (content, thickness) == expected[:2] and content is not None and len(steps) == cell["steps"] and steps == expected[2]:
            # Equal answers at every step are equal collision sets: the CPU cell's verdicts (how many pairs collide, were
            # missed and were false alarms) are this cell's. Why a miss was missed (culled or tested) is not carried over.
            for field in ("colliding", "missed", "false_alarms", "reported"):
                cell[field] = reference.get(field, 0)
            cell["verified"] = True
            cell["verified_by"] = "parity"
            agreed += 1
        else:
            cell["answers_differ"] = True
            differed += 1
    return agreed, differed


def main(out, cpu_map=None):
    summaries = json.load(open(os.path.join(out, "raw", "map.json")))
    parity = verify_by_parity(summaries, out, cpu_map) if cpu_map else None
    cells = {}
    for s in summaries:
        name, res, spf = parse_scene(s["scene"])
        family, narrow, backend = kind(s["strategy"])
        cells[(name, res, spf, narrow, backend, family)] = s
    panels = sorted({(narrow, b, f) for (_, _, _, narrow, b, f) in cells if f in FAMILY_LABEL},
                    key=lambda p: (p[1], p[0], p[2]))
    keys = sorted({(n, r, narrow, b) for (n, r, spf, narrow, b, f) in cells},
                  key=lambda k: (SCENES.index(k[0]) if k[0] in SCENES else 99, k[1], k[2], k[3]))
    spfs = sorted({spf for (_, _, spf, _, _, _) in cells})
    rows, points, skip_points, reasons_rows, missed_rows = [], defaultdict(list), defaultdict(list), [], []
    stage_sums = defaultdict(lambda: defaultdict(lambda: defaultdict(float)))  # (panel, spf) -> family -> stage -> ms
    no_contact = unverified = 0
    for name, res, narrow, backend in keys:
        for family in ("apccd", "boxes"):
            panel = (narrow, backend, family)
            if panel not in panels:
                continue
            row = f"| {name} | {res} | {panel_name(panel).rsplit(',', 1)[0]} | {backend} |"
            for spf in spfs:
                full = cells.get((name, res, spf, narrow, backend, "full"))
                apccd = cells.get((name, res, spf, narrow, backend, family))
                noskip = cells.get((name, res, spf, narrow, backend, "noskip")) if family == "apccd" else None
                session_cell = cells.get((name, res, spf, narrow, backend, "apccd"), apccd)
                if not full or not apccd:
                    row += " - |"
                    continue
                steps = apccd["steps"]
                starts = session_cell["counters"].get("session_start", {}).get("mean", 1.0) * steps
                length = steps / starts if starts > 0 else float("inf")
                ratio = full["ms_per_step_mean"] / apccd["ms_per_step_mean"]
                families = (("full", full), (family, apccd)) + ((("apccd:skip=off", noskip),) if noskip else ())
                if family == "apccd":  # full's misses once per panel pair
                    for label, cell in families:
                        if cell and cell.get("missed", 0) > 0:
                            missed_rows.append(f"| {name} r{res} spf{spf} | {narrow} | {backend} | {label} | {cell['missed']} of {cell['colliding']} |")
                elif apccd.get("missed", 0) > 0:
                    missed_rows.append(f"| {name} r{res} spf{spf} | {narrow} | {backend} | apccd:heuristic=boxes | {apccd['missed']} of {apccd['colliding']} |")
                if not all(c.get("verified", False) for _, c in families):
                    unverified += 1
                    row += f" unverified ({ratio:.2f}x) |"
                    continue
                if not cell_has_contact(full) or not cell_has_contact(apccd):
                    no_contact += 1
                    row += f" no contact ({ratio:.2f}x) |"
                    continue
                bold = "**" if ratio >= 1 else ""
                if noskip:
                    skipping = noskip["ms_per_step_mean"] / apccd["ms_per_step_mean"]
                    row += f" {bold}{ratio:.2f}x{bold} ({length:.1f}; {skipping:.2f}x) |"
                    skippable = sum(noskip["stage_ms_mean"].get(stage, 0.0) for stage in SKIPPABLE)
                    rest = noskip["ms_per_step_mean"] - skippable
                    bound = noskip["ms_per_step_mean"] / rest if rest > 0 else float("inf")
                    skip_points[panel].append((name, res, spf, skipping, length, bound))
                else:
                    row += f" {bold}{ratio:.2f}x{bold} ({length:.1f}) |"
                points[panel].append((name, res, spf, ratio, length))
                for label, cell in families:
                    sums = stage_sums[(panel, spf)][label]
                    for stage, value in cell["stage_ms_mean"].items():
                        sums[stage] += value
                    sums[""] += cell["ms_per_step_mean"]
                if family == "apccd":
                    ended = {r: apccd["counters"].get("session_end_" + r, {}).get("mean", 0.0) * steps for r in REASONS}
                    total = sum(ended.values())
                    if total > 0:
                        shares = ", ".join(f"{r} {100 * v / total:.0f}%" for r, v in ended.items() if v > 0)
                        reasons_rows.append(f"| {name} r{res} spf{spf} | {narrow} | {backend} | {steps} | {starts:.0f} | {length:.1f} | {shares} |")
            rows.append(row)
    best = max(((p, panel) for panel, ps in points.items() for p in ps), key=lambda pp: pp[0][3], default=None)
    counted = sum(len(ps) for ps in points.values())
    with open(os.path.join(out, "map.md"), "w") as md:
        md.write("# Where apccd's skipping pays: full / apccd\n\n")
        md.write(open(os.path.join(out, "raw", "command.txt")).read().replace("# ", "    # ").replace("\nbuild/", "\n    build/").replace("\nccdbench", "\n    ccdbench") + "\n")
        run = dict(line.rstrip("\n").split("\t") for line in open(os.path.join(out, "raw", "run.tsv")))
        any_cell = summaries[0] if summaries else {}
        revision = any_cell.get("git_revision", "?")
        devices = sorted({f"{s['provenance']['opencl_device']} (driver {s['provenance'].get('opencl_driver', '?')})"
                          for s in summaries if s.get("provenance", {}).get("opencl_device")})
        md.write(f"Machine: {any_cell.get('machine', '?')}, {any_cell.get('threads', '?')} threads"
                 f"{'; OpenCL device: ' + ', '.join(devices) if devices else ''}; ccdbench revision {revision}; "
                 f"profile {run.get('profile')}, {run.get('elapsed_s')} s of runs. Each cell: mean ms per step of full over "
                 "apccd with the same narrow phase and backend (> 1: apccd faster, in bold); in parentheses apccd's mean "
                 "session length in frames and, for the paper's front end, what skipping alone gives: apccd:skip=off's mean "
                 "ms over apccd's (the same front end, every step a session start). Every cell is verified against the exact "
                 "truth; one that is not says so and counts nowhere.\n\n")
        if parity:
            md.write(f"Verified by parity with the CPU map ({parity[0]} cells): these cells ran without the exact truth, and "
                     "every step's digest of reported pairs and TOI bits equals that of the same strategy's CPU cell, which "
                     f"was verified against it, on the same scene content at the same δ (map.py --parity); {parity[1]} "
                     "cells whose answers differ anywhere, or that could not be compared, stay unverified.\n\n")
        if best:
            (bname, bres, bspf, bratio, blength), bpanel = best
            md.write(f"Best cell: {bname} r{bres} spf{bspf}, {panel_name(bpanel)}: {bratio:.2f}x (sessions of {blength:.1f} frames). "
                     f"Cells where apccd is faster: {sum(1 for ps in points.values() for p in ps if p[3] >= 1)} of {counted} "
                     f"with contact; {no_contact} cells without a colliding pair; {unverified} unverified.\n\n")
        md.write("At a glance, the median over the scenes and resolutions with contact of: full / apccd; apccd:skip=off / "
                 "apccd (skipping's own share); the most skipping could give, were every skipped frame free "
                 "(apccd:skip=off's ms over its ms less its refit and traversal stages); and the sessions' mean length:\n\n")
        md.write("| narrow phase, backend | " + " | ".join(f"spf {s}" for s in spfs) + " |\n|---|" + "---|" * len(spfs) + "\n")
        for panel in panels:
            entries = []
            for spf in spfs:
                ratios = [p[3] for p in points.get(panel, []) if p[2] == spf]
                lengths = [p[4] for p in points.get(panel, []) if p[2] == spf]
                skips = [p[3] for p in skip_points.get(panel, []) if p[2] == spf]
                bounds = [p[5] for p in skip_points.get(panel, []) if p[2] == spf]
                if not ratios:
                    entries.append("-")
                elif skips:
                    entries.append(f"{median(ratios):.2f}x; {median(skips):.2f}x; at most {median(bounds):.2f}x; {median(lengths):.1f} frames")
                else:
                    entries.append(f"{median(ratios):.2f}x; {median(lengths):.1f} frames")
            md.write(f"| {panel_name(panel)} | " + " | ".join(entries) + " |\n")
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
        md.write(stage_tables(panels, spfs, stage_sums))
        md.write("## Why apccd's sessions ended\n\n| cell | narrow phase | backend | steps | sessions | mean length | ended by |\n"
                 "|---|---|---|---:|---:|---:|---|\n")
        md.write("\n".join(reasons_rows) + "\n\n")
        md.write("## Missed collisions\n\n")
        md.write(miss_summary(cells) + "\n\n")
        if missed_rows:
            md.write("| cell | narrow phase | backend | strategy | missed |\n|---|---|---|---|---|\n" + "\n".join(missed_rows) + "\n")
        else:
            md.write("None in any cell.\n")
    plot(points, skip_points, spfs, panels, os.path.join(out, "map.png"))


def miss_summary(cells):
    """Misses over the verified cells: the conservative narrow phase's (must be none) and, with cubic64 (which misses
    pairs it tests), whether each apccd variant misses exactly what full misses on the same scene."""
    conservative = [c for k, c in cells.items() if k[3] == "conservative" and c.get("verified")]
    missed = sum(c.get("missed", 0) for c in conservative)
    same = differ = 0
    for (name, res, spf, narrow, backend, family), cell in cells.items():
        full = cells.get((name, res, spf, narrow, backend, "full"))
        if narrow != "cubic64" or family == "full" or not full or not (cell.get("verified") and full.get("verified")):
            continue
        if cell.get("missed", 0) == full.get("missed", 0):
            same += 1
        else:
            differ += 1
    return (f"Conservative narrow phase: {missed} missed over {len(conservative)} verified cells "
            f"({sum(c.get('colliding', 0) for c in conservative if kind(c['strategy'])[0] == 'full')} colliding pairs, "
            "summed over full's cells). cubic64 misses pairs it tests: each apccd variant's cell misses as many pairs as "
            f"full's on the same scene in {same} of {same + differ} cells.")


def stage_tables(panels, spfs, stage_sums):
    """Where each strategy's time goes: for each panel and motion, ms per step summed over the cells with contact,
    total then the stages that take at least STAGE_SHARE_SHOWN of it, largest first."""
    text = ["## Where the time goes, stage by stage\n",
            "Mean ms per step summed over the cells with contact of each motion (the cells the medians above count): the "
            f"total, then each stage that takes at least {100 * STAGE_SHARE_SHOWN:.0f}% of it. What a skipped frame saves is "
            "apccd's refit (`update`) and traversal; the front end (`front end`, `distance heuristic`), the pairs across "
            "objects (`object pairs`) and the narrow phase (`back end`) run every step. On the OpenCL backend, `launch and "
            "wait` is the host's time between the device's stages.\n"]
    for panel in panels:
        families = ["full", "apccd:skip=off", panel[2]] if panel[2] == "apccd" else ["full", panel[2]]
        header = ["steps per frame"] + [("full" if f == "full" else "apccd" + FAMILY_LABEL.get(f, "") if f in FAMILY_LABEL else f) for f in families]
        lines = [f"\n### {panel_name(panel)}\n", "| " + " | ".join(header) + " |", "|---|" + "---|" * len(families)]
        for spf in spfs:
            by_family = stage_sums.get((panel, spf))
            if not by_family:
                continue
            entries = []
            for family in families:
                sums = by_family.get(family)
                if not sums:
                    entries.append("-")
                    continue
                total = sums[""]
                shown = sorted(((v, s) for s, v in sums.items() if s and v >= STAGE_SHARE_SHOWN * total), reverse=True)
                entries.append(f"{total:.1f}: " + ", ".join(f"{s} {v:.1f}" for v, s in shown))
            lines.append(f"| {spf} | " + " | ".join(entries) + " |")
        text.append("\n".join(lines) + "\n")
    return "\n".join(text) + "\n"


def median(values):
    values = sorted(values)
    if not values:
        return float("nan")
    middle = len(values) // 2
    return values[middle] if len(values) % 2 else (values[middle - 1] + values[middle]) / 2


def cell_has_contact(cell):
    return cell.get("colliding", 0) > 0


def plot(points, skip_points, spfs, panels, path):
    panels = [p for p in panels if points.get(p)]
    if not panels:
        return
    fig, axes = plt.subplots(2, len(panels), figsize=(4.6 * len(panels), 8), squeeze=False, sharey="row", sharex=True)
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
            ticks = [0.35, 0.5, 0.71, 1, 1.41, 2, 2.83]
            ax.set_yticks(ticks)
            ax.set_yticklabels([str(t) for t in ticks])
            ax.grid(True, which="both", alpha=0.3)
            if row == 0:
                ax.set_title(panel_name(panel), fontsize=10)
            if row == 1:
                ax.set_xlabel("CCD steps per simulated frame\n(less motion per step to the right)")
                if not series.get(panel):
                    ax.text(0.5, 0.5, "no skip=off run\nfor this front end", transform=ax.transAxes, ha="center", va="center", fontsize=8)
            if column == 0:
                ax.set_ylabel(ylabel)
    axes[0][-1].legend(fontsize=7, loc="best", title="scene (o, s, D: smallest to largest resolution)", title_fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) == 2:
        main(sys.argv[1])
    elif len(sys.argv) == 4 and sys.argv[2] == "--parity":
        main(sys.argv[1], sys.argv[3])
    else:
        sys.exit(__doc__)
