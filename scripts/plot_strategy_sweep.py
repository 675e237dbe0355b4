#!/usr/bin/python3
"""Draws the trade of a strategy sweep from a `ccdbench run --json` summary: for each scene, ms per step against
missed collisions and against false alarms, one point per strategy spec (knob setting and narrow phase)."""
import json
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def label(strategy):
    head, _, keys = strategy.partition(":")
    narrow = head.split("+")[1] if "+" in head else ""
    knobs = [k for k in keys.split(":") if k.split("=")[0] in
             {"skip", "nf_min", "nf_max", "local", "global", "dangling_max", "pending_max", "heuristic", "history", "object_pairs", "inflation_max"}]
    defaults = {"skip=on", "nf_min=1", "nf_max=8", "local=1", "global=0.25", "dangling_max=0.05", "pending_max=4", "heuristic=on", "history=off", "object_pairs=fresh", "inflation_max=0.5"}
    changed = [k for k in knobs if k not in defaults]
    return f"{head.split('+')[0]}+{narrow}" + (" " + " ".join(changed) if changed else "")


def main(summary_path, image_path):
    rows = json.load(open(summary_path))
    scenes = sorted({r["scene"] for r in rows})
    figure, axes = plt.subplots(len(scenes), 2, figsize=(12, 3.6 * len(scenes)), squeeze=False)
    for (missed_axis, alarm_axis), scene in zip(axes, scenes):
        for r in (r for r in rows if r["scene"] == scene):
            for axis, field in ((missed_axis, "missed"), (alarm_axis, "false_alarms")):
                axis.scatter(r["ms_per_step"], r.get(field, 0))
                axis.annotate(label(r["strategy"]), (r["ms_per_step"], r.get(field, 0)), fontsize=6,
                              xytext=(2, 2), textcoords="offset points")
        for axis, title in ((missed_axis, "missed"), (alarm_axis, "false alarms")):
            axis.set_xscale("log")
            axis.set_xlabel("ms per step (median)")
            axis.set_title(f"{scene}: {title}")
            axis.grid(True, which="both", alpha=0.3)
    figure.tight_layout()
    figure.savefig(image_path, dpi=100)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: plot_strategy_sweep.py SUMMARY.json IMAGE.png")
    main(sys.argv[1], sys.argv[2])
