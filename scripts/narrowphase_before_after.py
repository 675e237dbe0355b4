#!/usr/bin/env python3
"""Before/after table of the narrow phases from two `ccdbench queries --json` score files of the same queries, run
one after the other in one invocation (scripts/narrowphase-before-after.sh): for every method present in both (the
spec's keys may differ: rows are matched by the method's name before its first ':' and by file), FN, FP, TOI late,
the TOI error's median / p99 / max and ns per query, before -> after. Prints Markdown.

Usage: narrowphase_before_after.py TITLE BEFORE.json AFTER.json [FILE_FILTER]"""

import json
import sys


def rows(path):
    with open(path) as handle:
        return json.load(handle)


def number(value):
    if value is None:
        return "-"
    if isinstance(value, int):
        return f"{value:,}"
    if value == 0:
        return "0"
    if abs(value) >= 100:
        return f"{value:,.0f}"
    return f"{value:.3g}"


def main():
    if len(sys.argv) not in (4, 5):
        sys.exit(__doc__)
    title, before_path, after_path = sys.argv[1:4]
    wanted = sys.argv[4] if len(sys.argv) == 5 else None
    before = {(r["method"].split(":")[0], r["file"]): r for r in rows(before_path)}
    print(f"### {title}\n")
    print("| method | file | FN | FP | TOI late | TOI error median | p99 | max | ns/query |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for after in rows(after_path):
        key = (after["method"].split(":")[0], after["file"])
        if key not in before or (wanted and wanted not in after["file"]):
            continue
        old = before[key]
        cells = []
        for field in ("false_negatives", "false_positives", "toi_late", "toi_error_median", "toi_error_p99", "toi_error_max",
                      "ns_per_query"):
            cells.append(f"{number(old.get(field))} → {number(after.get(field))}")
        name = after["file"] if after["file"] == "(all)" else "/".join(after["file"].split("/")[-3:])
        print(f"| `{key[0]}` | {name} | " + " | ".join(cells) + " |")
    print()


if __name__ == "__main__":
    main()
