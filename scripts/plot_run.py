#!/usr/bin/python3
"""Draws a `ccdbench run --report DIR` page's plots from DIR/steps.json: ms per step over the steps (one panel per
scene, one line per strategy) and the median stage breakdown per scene and strategy (stacked bars)."""
import json
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def short(strategy):
    return strategy.split(":")[0]


def main(directory):
    steps = json.load(open(f"{directory}/steps.json"))
    scenes = sorted({s["scene"] for s in steps})
    columns = min(3, len(scenes))
    rows = (len(scenes) + columns - 1) // columns
    figure, axes = plt.subplots(rows, columns, figsize=(5 * columns, 3.5 * rows), squeeze=False)
    for axis, scene in zip(axes.flat, scenes):
        for strategy in sorted({s["strategy"] for s in steps if s["scene"] == scene}):
            points = sorted((s["step"], s["ms"]) for s in steps if s["scene"] == scene and s["strategy"] == strategy)
            axis.plot([p[0] for p in points], [p[1] for p in points], marker=".", label=short(strategy))
        axis.set_title(scene)
        axis.set_xlabel("step")
        axis.set_ylabel("ms per step")
        axis.set_yscale("log")
        axis.legend(fontsize=7)
    for axis in list(axes.flat)[len(scenes):]:
        axis.axis("off")
    figure.tight_layout()
    figure.savefig(f"{directory}/ms_per_step.png", dpi=100)

    cells = sorted({(s["scene"], s["strategy"]) for s in steps})
    stages = sorted({stage for s in steps for stage in s["stages"]})
    figure, axis = plt.subplots(figsize=(max(6, 0.9 * len(cells)), 4.5))
    bottom = [0.0] * len(cells)
    for stage in stages:
        heights = []
        for scene, strategy in cells:
            values = [s["stages"].get(stage, 0.0) for s in steps if s["scene"] == scene and s["strategy"] == strategy]
            heights.append(statistics.median(values))
        axis.bar(range(len(cells)), heights, bottom=bottom, label=stage)
        bottom = [b + h for b, h in zip(bottom, heights)]
    axis.set_xticks(range(len(cells)))
    axis.set_xticklabels([f"{scene}\n{short(strategy)}" for scene, strategy in cells], rotation=60, ha="right", fontsize=7)
    axis.set_ylabel("median ms per step")
    axis.set_yscale("symlog", linthresh=0.1)
    axis.legend()
    figure.tight_layout()
    figure.savefig(f"{directory}/stages.png", dpi=100)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: plot_run.py REPORT_DIR")
    main(sys.argv[1])
