#!/usr/bin/python3
"""Draws the narrow phases' trade of speed for accuracy from a `ccdbench queries --report` scores.json: time per
query against false negatives, false positives and the TOI error (99th percentile, and max as open markers), one
line per variant and swept key (a row belongs to the line of the one key whose value differs from the family's most
common value; the defaults' row to every line of its family)."""
import collections
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def keys_of(method):
    return dict(part.split("=", 1) for part in method.split(":")[1:] if "=" in part)


def lines(rows):
    families = collections.defaultdict(list)
    for row in rows:
        families[row["method"].split(":")[0]].append(row)
    out = {}
    for family, members in sorted(families.items()):
        keys = [keys_of(r["method"]) for r in members]
        names = sorted({k for ks in keys for k in ks})
        mode = {k: collections.Counter(ks.get(k) for ks in keys).most_common(1)[0][0] for k in names}
        varied = {}
        for row, ks in zip(members, keys):
            differing = [k for k in names if ks.get(k) != mode[k]]
            varied.setdefault(tuple(differing), []).append(row)
        swept = [d for d in varied if len(d) == 1]
        if not swept:
            out[family] = members
            continue
        defaults = varied.get((), [])
        for d in swept:
            out[f"{family} ({d[0]})"] = varied[d] + defaults
    return out


def label(row, line):
    swept = line[line.find("(") + 1:-1] if "(" in line else None
    keys = keys_of(row["method"])
    return f"{swept}={keys[swept]}" if swept in keys else ",".join(f"{k}={v}" for k, v in keys.items() if k != "max_iterations")


def main(scores_path, image_path):
    rows = [r for r in json.load(open(scores_path)) if r["file"] == "(all)"]
    figure, (misses, alarms, toi) = plt.subplots(1, 3, figsize=(18, 5))
    for line, points in lines(rows).items():
        points = sorted(points, key=lambda r: r["ns_per_query"])
        x = [max(r["ns_per_query"], 1) for r in points]
        labels = [label(r, line) for r in points]
        for axis, field in ((misses, "false_negatives"), (alarms, "false_positives")):
            y = [r[field] for r in points]
            axis.plot(x, y, marker="o", label=line)
            for xi, yi, text in zip(x, y, labels):
                axis.annotate(text, (xi, yi), fontsize=6, xytext=(2, 2), textcoords="offset points")
        # null: nothing was checked (no TOI on a colliding query), so nothing to draw
        if all(r.get("toi_error_p99") is not None for r in points):
            floor = 1e-18  # an error of 0 drawn at the axis' floor
            p99 = [max(r["toi_error_p99"], floor) for r in points]
            drawn = toi.plot(x, p99, marker="o", label=line)[0]
            toi.scatter(x, [max(r["toi_error_max"], floor) for r in points], facecolors="none", edgecolors=drawn.get_color())
            for xi, yi, text in zip(x, p99, labels):
                toi.annotate(text, (xi, yi), fontsize=6, xytext=(2, 2), textcoords="offset points")
    for axis, title in ((misses, "missed collisions (FN)"), (alarms, "false alarms (FP)"),
                        (toi, "TOI error, fraction of the step: p99 (line), max (open)")):
        axis.set_xscale("log")
        axis.set_xlabel("ns per query (median over repeats)")
        axis.set_title(title)
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=7)
    toi.set_yscale("log")
    figure.suptitle(f"narrow phases on {rows[0]['queries'] if rows else 0} queries")
    figure.tight_layout()
    figure.savefig(image_path, dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit("usage: plot_narrowphase.py SCORES.json IMAGE.png")
    main(sys.argv[1], sys.argv[2])
