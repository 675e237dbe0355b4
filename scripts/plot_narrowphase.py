#!/usr/bin/python3
"""Draws the narrow phases' trade of speed for accuracy from a `ccdbench queries --report` scores.json:
time per query against false negatives and false positives, one line per variant across its swept parameter."""
import json
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def main(scores_path, image_path):
    rows = [r for r in json.load(open(scores_path)) if r["file"] == "(all)"]
    families = {}
    for row in rows:
        family = row["method"].split(":")[0]
        families.setdefault(family, []).append(row)
    figure, (misses, alarms) = plt.subplots(1, 2, figsize=(12, 4.5))
    for family, points in sorted(families.items()):
        points.sort(key=lambda r: r["ns_per_query"])
        x = [max(r["ns_per_query"], 1) for r in points]
        labels = [re.sub(r":max_iterations=\d+", "", re.sub(r"^[^:]*:?", "", r["method"])) for r in points]
        for axis, field in ((misses, "false_negatives"), (alarms, "false_positives")):
            y = [r[field] for r in points]
            axis.plot(x, y, marker="o", label=family)
            for xi, yi, label in zip(x, y, labels):
                axis.annotate(label, (xi, yi), fontsize=6, xytext=(2, 2), textcoords="offset points")
    for axis, title in ((misses, "missed collisions (FN)"), (alarms, "false alarms (FP)")):
        axis.set_xscale("log")
        axis.set_xlabel("ns per query (median over repeats)")
        axis.set_title(title)
        axis.grid(True, which="both", alpha=0.3)
        axis.legend()
    figure.suptitle(f"narrow phases on {rows[0]['queries'] if rows else 0} queries")
    figure.tight_layout()
    figure.savefig(image_path, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: plot_narrowphase.py SCORES.json IMAGE.png")
    main(sys.argv[1], sys.argv[2])
