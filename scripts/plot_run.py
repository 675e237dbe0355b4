#!/usr/bin/python3
"""Draws a `ccdbench run --report DIR` page's plots from DIR/summaries.json and DIR/steps.json:

- speedup.png: each cell's speed-up over its baseline (`full` with the same narrow phase, measured in the same
  invocation), one bar per strategy and scene, on a linear axis with 1x marked;
- verdicts.png: per cell, colliding pairs, missed pairs and false alarms (a missed pair is a defect; a false alarm
  a cost), so that "0 missed" is read against how much there was to miss;
- stages.png: the median ms per step of each stage, stacked on a linear axis, so that a stage's share of the bar is
  its share of the time;
- ms_per_step.png: ms per step over the steps, one panel per scene and line per strategy.
"""
import json
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def short(summary):
    """A strategy's name without its defaults, with δ: 'apccd+cubic64 (δ 0)'."""
    strategy = summary["strategy"]
    head = strategy.split(":")[0]
    if ":backend=opencl" in strategy:
        head += " (OpenCL)"
    if ":filter=on" in strategy:
        head += " filter"
    return f"{head} δ {summary['thickness']:.3g}"


def by_scene(summaries):
    """The scenes in order of first appearance, each with its cells."""
    scenes = []
    for s in summaries:
        if s["scene"] not in scenes:
            scenes.append(s["scene"])
    return [(scene, [s for s in summaries if s["scene"] == scene]) for scene in scenes]


def panels(count, height_per_row):
    """One panel per scene, two columns."""
    columns = min(2, count)
    rows = (count + columns - 1) // columns
    figure, axes = plt.subplots(rows, columns, figsize=(7.5 * columns, height_per_row * rows + 0.6), squeeze=False)
    for axis in list(axes.flat)[count:]:
        axis.axis("off")
    return figure, list(axes.flat)


def speedups(summaries, directory):
    scenes = by_scene(summaries)
    figure, axes = panels(len(scenes), 0.22 * max(len(cells) for _, cells in scenes) + 1.0)
    for axis, (scene, cells) in zip(axes, scenes):
        cells = [s for s in cells if s.get("speedup") is not None]
        axis.barh(range(len(cells)), [s["speedup"] for s in cells], color="tab:blue")
        axis.axvline(1.0, color="black", linewidth=0.8)
        axis.set_yticks(range(len(cells)))
        axis.set_yticklabels([short(s) for s in cells], fontsize=7)
        axis.invert_yaxis()
        axis.set_title(scene, fontsize=9)
        axis.set_xlabel("speed-up over full (same narrow phase and δ, same invocation); > 1: faster", fontsize=7)
    figure.tight_layout()
    figure.savefig(f"{directory}/speedup.png", dpi=100)


def verdicts(summaries, directory):
    scenes = by_scene([s for s in summaries if s.get("verified")])
    if not scenes:
        return
    figure, axes = panels(len(scenes), 0.3 * max(len(cells) for _, cells in scenes) + 1.0)
    height = 0.27
    for axis, (scene, cells) in zip(axes, scenes):
        y = range(len(cells))
        axis.barh([i - height for i in y], [s["colliding"] for s in cells], height, label="colliding (truth)", color="tab:gray")
        axis.barh(list(y), [s["missed"] for s in cells], height, label="missed", color="tab:red")
        axis.barh([i + height for i in y], [s["false_alarms"] for s in cells], height, label="false alarms", color="tab:orange")
        for i, s in enumerate(cells):
            axis.annotate(f" {s['missed']} missed", (max(s["missed"], 0), i), va="center", fontsize=6, color="tab:red")
        axis.set_yticks(list(y))
        axis.set_yticklabels([short(s) for s in cells], fontsize=7)
        axis.invert_yaxis()
        axis.set_xscale("symlog", linthresh=1)
        axis.set_title(scene, fontsize=9)
        axis.set_xlabel("pairs over all steps (symlog)", fontsize=7)
    axes[0].legend(fontsize=7, loc="lower right")
    figure.tight_layout()
    figure.savefig(f"{directory}/verdicts.png", dpi=100)


def stages(summaries, directory):
    names = sorted({stage for s in summaries for stage in s["stage_ms"]})
    colors = {stage: plt.get_cmap("tab20")(i % 20) for i, stage in enumerate(names)}
    scenes = by_scene(summaries)
    figure, axes = panels(len(scenes), 0.22 * max(len(cells) for _, cells in scenes) + 1.0)
    for axis, (scene, cells) in zip(axes, scenes):
        left = [0.0] * len(cells)
        for stage in names:
            widths = [s["stage_ms"].get(stage, 0.0) for s in cells]
            axis.barh(range(len(cells)), widths, left=left, color=colors[stage], label=stage)
            left = [a + b for a, b in zip(left, widths)]
        axis.set_yticks(range(len(cells)))
        axis.set_yticklabels([short(s) for s in cells], fontsize=7)
        axis.invert_yaxis()
        axis.set_title(scene, fontsize=9)
        axis.set_xlabel("median ms per step, by stage (linear: a stage's share of the bar is its share of the time)", fontsize=7)
    handles = [plt.Rectangle((0, 0), 1, 1, color=colors[stage]) for stage in names]
    figure.legend(handles, names, loc="lower center", ncol=min(6, len(names)), fontsize=7)
    figure.tight_layout(rect=(0, 0.06, 1, 1))
    figure.savefig(f"{directory}/stages.png", dpi=100)


def times(steps, directory):
    scenes = sorted({s["scene"] for s in steps})
    columns = min(3, len(scenes))
    rows = (len(scenes) + columns - 1) // columns
    figure, axes = plt.subplots(rows, columns, figsize=(5 * columns, 3.5 * rows), squeeze=False)
    for axis, scene in zip(axes.flat, scenes):
        cells = sorted({(s["strategy"], s["thickness"]) for s in steps if s["scene"] == scene})
        for strategy, thickness in cells:
            points = sorted((s["step"], s["ms"]) for s in steps
                            if s["scene"] == scene and s["strategy"] == strategy and s["thickness"] == thickness)
            label = short({"strategy": strategy, "thickness": thickness})
            axis.plot([p[0] for p in points], [p[1] for p in points], marker=".", label=label)
        axis.set_title(scene)
        axis.set_xlabel("step")
        axis.set_ylabel("ms per step (log)")
        axis.set_yscale("log")
        axis.legend(fontsize=6)
    for axis in list(axes.flat)[len(scenes):]:
        axis.axis("off")
    figure.tight_layout()
    figure.savefig(f"{directory}/ms_per_step.png", dpi=100)


def main(directory):
    summaries = json.load(open(f"{directory}/summaries.json"))
    steps = json.load(open(f"{directory}/steps.json"))
    speedups(summaries, directory)
    verdicts(summaries, directory)
    stages(summaries, directory)
    times(steps, directory)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: plot_run.py REPORT_DIR")
    main(sys.argv[1])
