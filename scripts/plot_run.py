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


def cell_labels(summaries):
    return [f"{s['scene']}\n{short(s)}" for s in summaries]


def speedups(summaries, directory):
    scenes = sorted({s["scene"] for s in summaries})
    figure, axes = plt.subplots(len(scenes), 1, figsize=(9, 2.2 * len(scenes) + 0.8), squeeze=False)
    for axis, scene in zip(axes.flat, scenes):
        cells = [s for s in summaries if s["scene"] == scene and s.get("speedup") is not None]
        axis.barh(range(len(cells)), [s["speedup"] for s in cells], color="tab:blue")
        axis.axvline(1.0, color="black", linewidth=0.8)
        axis.set_yticks(range(len(cells)))
        axis.set_yticklabels([short(s) for s in cells], fontsize=7)
        axis.set_title(scene, fontsize=9)
        axis.set_xlabel("speed-up over full (same narrow phase, same invocation); > 1: faster", fontsize=8)
    figure.tight_layout()
    figure.savefig(f"{directory}/speedup.png", dpi=100)


def verdicts(summaries, directory):
    verified = [s for s in summaries if s.get("verified")]
    if not verified:
        return
    figure, axis = plt.subplots(figsize=(max(7, 0.55 * len(verified)), 4.5))
    x = range(len(verified))
    width = 0.27
    axis.bar([i - width for i in x], [s["colliding"] for s in verified], width, label="colliding (truth)", color="tab:gray")
    axis.bar(list(x), [s["missed"] for s in verified], width, label="missed", color="tab:red")
    axis.bar([i + width for i in x], [s["false_alarms"] for s in verified], width, label="false alarms", color="tab:orange")
    for i, s in enumerate(verified):
        axis.annotate(str(s["missed"]), (i, s["missed"]), ha="center", va="bottom", fontsize=6, color="tab:red")
    axis.set_xticks(list(x))
    axis.set_xticklabels(cell_labels(verified), rotation=70, ha="right", fontsize=6)
    axis.set_ylabel("pairs over all steps (symlog)")
    axis.set_yscale("symlog", linthresh=1)
    axis.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(f"{directory}/verdicts.png", dpi=100)


def stages(summaries, directory):
    names = sorted({stage for s in summaries for stage in s["stage_ms"]})
    figure, axis = plt.subplots(figsize=(max(7, 0.55 * len(summaries)), 4.5))
    bottom = [0.0] * len(summaries)
    for stage in names:
        heights = [s["stage_ms"].get(stage, 0.0) for s in summaries]
        axis.bar(range(len(summaries)), heights, bottom=bottom, label=stage)
        bottom = [b + h for b, h in zip(bottom, heights)]
    axis.set_xticks(range(len(summaries)))
    axis.set_xticklabels(cell_labels(summaries), rotation=70, ha="right", fontsize=6)
    axis.set_ylabel("median ms per step, by stage (linear)")
    axis.legend(fontsize=7, ncol=2)
    figure.tight_layout()
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
