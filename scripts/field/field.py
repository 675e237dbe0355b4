#!/usr/bin/python3
"""The field report's data and tables (reports/field/README.md).

  field.py sample DATA FIELD_QUERIES WORK   the query sets the report scores, sampled as the report says, into WORK
  field.py relabel ANSWERS WORK             WORK/queries/main labelled at δ by the exact reference's answers
  field.py collect WORK                     ccdbench's outputs in WORK condensed into reports/field/data/*.csv
  field.py gpu OUT_DIR...                   scripts/field/gpu.sh's outputs (one folder per call on the GPU machine)
                                            condensed into reports/field/data/gpu.csv and gpu.json
  field.py tables [--check]                 the Markdown tables of reports/field/README.md and README.md, from the
                                            committed data; --check writes nothing and exits 1 naming each table that
                                            differs from what the data gives (the CTest field.tables)

Standard library only, for Debian's /usr/bin/python3.
"""
import csv
import json
import math
import os
import re
import shlex
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DATA = os.path.join(ROOT, "reports", "field", "data")
KINDS = ("vertex-face", "edge-edge")
# The sets, in the tables' order: where each comes from under DATA_DIR or FIELD_QUERIES.
SETS = ("unit-tests", "cloth-funnel", "rod-twist", "handcrafted", "simulation")
# The most queries a set of one kind gives the report's tables (every k-th query of each file, k as small as keeps
# it under this), and the queries of each set and kind rescaled to each 2^k: the report's budget (README there).
MAIN_CAP = 300
SCALE_PER_SET = 4


def read_rows(path):
    with open(path) as f:
        return [line.strip() for line in f if line.strip()]


def sources(data_dir, field_queries):
    """(set, kind, name, rows with their truth in column 7) for every source file that is there."""
    found = []
    for kind in KINDS:
        folder = os.path.join(data_dir, "sample-queries", "unit-tests", kind)
        for name in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
            found.append(("unit-tests", kind, name[:-4], read_rows(os.path.join(folder, name))))
    for scene, step in (("cloth-funnel", "227"), ("rod-twist", "3036")):
        for kind, suffix in (("vertex-face", "vf"), ("edge-edge", "ee")):
            base = os.path.join(data_dir, "scalable-ccd-sample", scene)
            queries = os.path.join(base, "queries", step + suffix + ".csv")
            if not os.path.exists(queries):
                continue
            with open(os.path.join(base, "mma_bool", step + suffix + "_mma_bool.json")) as f:
                truth = json.load(f)
            rows = read_rows(queries)
            labelled = [row + "," + ("1" if truth[i // 8] else "0") for i, row in enumerate(rows)]
            found.append((scene, kind, step + suffix, labelled))
    for set_name in ("handcrafted", "simulation"):
        folder = os.path.join(field_queries, set_name)
        for scene in sorted(os.listdir(folder)) if os.path.isdir(folder) else []:
            for kind in KINDS:
                sub = os.path.join(folder, scene, kind)
                for name in sorted(os.listdir(sub)) if os.path.isdir(sub) else []:
                    found.append((set_name, kind, scene + "-" + name[:-4], read_rows(os.path.join(sub, name))))
    return found


def write_queries(path, queries):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        for query in queries:
            f.write("\n".join(query) + "\n")


def sample(data_dir, field_queries, work):
    """Writes WORK/queries/main (every k-th query of each file) and WORK/queries/scale (SCALE_PER_SET evenly spaced
    queries of each set and kind), and WORK/queries/sample.json saying what each holds."""
    found = sources(data_dir, field_queries)
    summary = {"main_cap": MAIN_CAP, "scale_per_set": SCALE_PER_SET, "sets": {}}
    for set_name in SETS:
        for kind in KINDS:
            files = [(name, rows) for s, k, name, rows in found if s == set_name and k == kind]
            if not files:
                continue
            total = sum(len(rows) // 8 for _, rows in files)
            stride = max(1, math.ceil(total / MAIN_CAP))
            kept = 0
            everything = []
            for name, rows in files:
                queries = [rows[8 * i:8 * i + 8] for i in range(len(rows) // 8)]
                everything += queries
                chosen = queries[::stride]
                kept += len(chosen)
                write_queries(os.path.join(work, "queries", "main", set_name, kind, name + ".csv"), chosen)
            step = len(everything) / SCALE_PER_SET
            scaled = [everything[int(i * step)] for i in range(min(SCALE_PER_SET, len(everything)))]
            write_queries(os.path.join(work, "queries", "scale", set_name, kind, "sample.csv"), scaled)
            summary["sets"][set_name + "/" + kind] = {"files": len(files), "queries": total, "every": stride, "main": kept,
                                                      "scale": len(scaled)}
    with open(os.path.join(work, "queries", "sample.json"), "w") as f:
        json.dump(summary, f, indent=1)
    for key, value in summary["sets"].items():
        print("field: %-24s %6d queries, every %d: %d; rescaled: %d" % (key, value["queries"], value["every"], value["main"], value["scale"]))


def relabel(answers, work):
    """WORK/queries/delta: WORK/queries/main with column 7 the exact reference's answer at δ (the data's is for 0)."""
    hits = {}
    with open(answers) as f:
        for row in csv.DictReader(f):
            if row["method"] == "exact":
                hits[(os.path.realpath(row["file"]), int(row["index"]))] = row["hit"]
    main = os.path.join(work, "queries", "main")
    for folder, _, names in os.walk(main):
        for name in names:
            path = os.path.join(folder, name)
            rows = read_rows(path)
            out = []
            for i, row in enumerate(rows):
                hit = hits[(os.path.realpath(path), i // 8)]
                if hit not in ("0", "1"):
                    sys.exit("field: %s query %d: the exact reference gave no answer (%s)" % (path, i // 8, hit))
                out.append(",".join(row.split(",")[:6] + [hit]))
            target = os.path.join(work, "queries", "delta", os.path.relpath(path, main))
            write_queries(target, [out[8 * i:8 * i + 8] for i in range(len(out) // 8)])


# ---------------------------------------------------------------------------------------------------------------
# collect: ccdbench's outputs, condensed


def method_key(spec, methods):
    """The methods.csv key of a resolved spec: a plugin by its file, a built-in narrow phase by its name."""
    if spec.startswith("plugin:"):
        name = os.path.basename(spec[len("plugin:"):].split(":")[0])
        for key, m in methods.items():
            if m["plugin"] == name:
                return key
        sys.exit("field: no method in methods.csv for plugin " + name)
    return spec.split(":")[0].split("+")[-1]


def set_of(path):
    """(set, kind) of a sampled file WORK/queries/TABLE/SET/KIND/NAME.csv."""
    parts = os.path.normpath(path).split(os.sep)
    return parts[-3], parts[-2]


def percentile(values, p):
    """The nearest-rank percentile, as ccdbench's harness/statistics.hpp."""
    if not values:
        return None
    ordered = sorted(values)
    rank = math.ceil(p / 100.0 * len(ordered))
    return ordered[min(max(rank, 1), len(ordered)) - 1]


def score_answers(answers, scores, methods, extra):
    """Rows per (set, kind, method) and per (all, all, method) from `queries --write-answers` and `--json`."""
    tally = {}

    def cell(key):
        return tally.setdefault(key, {"queries": 0, "positives": 0, "fn": 0, "fp": 0, "errors": 0, "toi_checked": 0,
                                      "toi_late": 0, "toi_errors": [], "ns": 0.0})

    with open(answers) as f:
        for row in csv.DictReader(f):
            set_name, kind = set_of(row["file"])
            key = method_key(row["method"], methods)
            for c in (cell((set_name, kind, key)), cell(("all", "all", key))):
                c["queries"] += 1
                label = row["label"] == "1"
                hit = row["hit"] == "1"
                c["positives"] += label
                c["errors"] += row["hit"] == "error"
                # A colliding query answered apart: an error (no answer) is counted apart, never as a miss here.
                c["fn"] += label and row["hit"] == "0"
                c["fp"] += hit and not label
                if hit and row["toi"] != "" and row["exact_toi"] != "":
                    toi, exact = float(row["toi"]), float(row["exact_toi"])
                    c["toi_checked"] += 1
                    c["toi_late"] += toi > exact
                    c["toi_errors"].append(abs(toi - exact))
    changed = {}
    for score in json.load(open(scores)):
        if score["file"] == "(all)":
            continue
        set_name, kind = set_of(score["file"])
        key = method_key(score["method"], methods)
        for k in ((set_name, kind, key), ("all", "all", key)):
            cell(k)["ns"] += score["ns_per_query"] * score["queries"]
            changed[k] = changed.get(k, 0) + score["changed_between_passes"]
    rows = []
    for (set_name, kind, key), c in tally.items():
        errors = c["toi_errors"]
        rows.append(dict(extra, set=set_name, kind=kind, method=key, queries=c["queries"], positives=c["positives"],
                         fn=c["fn"], fp=c["fp"], errors=c["errors"], toi_checked=c["toi_checked"], toi_late=c["toi_late"],
                         toi_error_mean=number(sum(errors) / len(errors)) if errors else "",
                         toi_error_p99=number(percentile(errors, 99)) if errors else "",
                         toi_error_max=number(max(errors)) if errors else "",
                         ns_per_query=number(c["ns"] / c["queries"]) if c["queries"] else "",
                         changed_between_passes=changed.get((set_name, kind, key), 0)))
    return rows


def number(value):
    return "%.3g" % value


def write_csv(name, rows, columns):
    os.makedirs(DATA, exist_ok=True)
    with open(os.path.join(DATA, name), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns, lineterminator="\n")
        writer.writeheader()
        for row in rows:
            writer.writerow({c: row.get(c, "") for c in columns})


QUERY_COLUMNS = ["table", "exponent", "thickness", "set", "kind", "method", "queries", "positives", "fn", "fp", "errors",
                 "toi_checked", "toi_late", "toi_error_mean", "toi_error_p99", "toi_error_max", "ns_per_query",
                 "changed_between_passes"]


def collect(work):
    methods = read_methods()
    out = os.path.join(work, "out")
    rows = score_answers(os.path.join(out, "main.answers.csv"), os.path.join(out, "main.json"), methods,
                         {"table": "main", "exponent": 0, "thickness": 0})
    meta = json.load(open(os.path.join(out, "meta.json")))
    rows += score_answers(os.path.join(out, "delta.answers.csv"), os.path.join(out, "delta.json"), methods,
                          {"table": "delta", "exponent": 0, "thickness": meta["delta"]})
    for k in meta["exponents"]:
        rows += score_answers(os.path.join(out, "scale%d.answers.csv" % k), os.path.join(out, "scale%d.json" % k), methods,
                              {"table": "scale", "exponent": k, "thickness": 0})
    write_csv("queries.csv", rows, QUERY_COLUMNS)

    stress = []
    for row in json.load(open(os.path.join(out, "stress.json"))):
        if row["family"] == "(all)":
            stress.append({"method": method_key(row["method"], methods), "thickness": "0" if row["thickness"] == "zero" else "positive",
                           "queries": row["queries"], "positives": row["positives"], "fn": row["false_negatives"],
                           "fp": row["false_positives"], "errors": row["errors"]})
    write_csv("stress.csv", stress, ["method", "thickness", "queries", "positives", "fn", "fp", "errors"])

    steps = []
    for name in ("steps-cloth-funnel.json", "steps-rod-twist.json", "steps-scenes.json", "steps-scenes-delta.json"):
        if not os.path.exists(os.path.join(out, name)):
            continue
        for s in json.load(open(os.path.join(out, name))):
            spec = s["spec"]
            key = "conservative" if spec == "full" else method_key(spec[len("full+"):], methods)
            # A public step run from its two frames is named after the file of its results (steps-cloth-funnel.json).
            scene = name[len("steps-"):-len(".json")] if s["scene"].startswith("frames/") else s["scene"]
            steps.append({"scene": scene, "thickness": number(s["thickness"]), "method": key, "steps": s["steps"], "colliding": s["colliding"],
                          "missed": s["missed"], "false_alarms": s["false_alarms"], "errors": s.get("errors", 0),
                          "toi_late": "%s of %s" % (s["toi_late"], s["toi_checked"]) if s.get("toi_checked") else "",
                          "ms_per_step": "%.4g" % s["ms_per_step"], "tests_per_step": "%.4g" % s["elementary_tests"]})
    write_csv("steps.csv", steps, ["scene", "thickness", "method", "steps", "colliding", "missed", "false_alarms", "errors", "toi_late",
                                   "ms_per_step", "tests_per_step"])
    with open(os.path.join(out, "manifest.tsv")) as f:
        builds = list(csv.DictReader(f, delimiter="\t"))
    write_csv("builds.csv", builds, ["library", "repository", "commit", "plugins", "patches"])
    with open(os.path.join(out, "stages.jsonl")) as f:
        stages = [json.loads(line) for line in f]
    meta["seconds"] = {s["stage"]: s["seconds"] for s in stages}
    meta["commands"] = [s["command"] for s in stages]
    with open(os.path.join(DATA, "run.json"), "w") as f:
        json.dump(meta, f, indent=1, sort_keys=True)
        f.write("\n")
    print("field: data written to " + os.path.relpath(DATA, ROOT))


# ---------------------------------------------------------------------------------------------------------------
# gpu: scripts/field/gpu.sh's stages (Scalable CCD's whole step beside ccdbench's OpenCL full, one invocation each)

GPU_COLUMNS = ["stage", "scene", "thickness", "method", "steps", "triangles", "colliding", "missed", "false_alarms", "errors",
               "toi_checked", "toi_late", "toi_error_p99", "changed_at_step", "ms_per_step", "device_mib"]
GPU_METHODS = (("full:backend=opencl", "opencl-conservative"), ("full+cubic64:backend=opencl", "opencl-cubic64"))
GPU_LABELS = {"opencl-conservative": "ccdbench full (OpenCL), conservative", "opencl-cubic64": "ccdbench full (OpenCL), cubic64",
              "scalable-ccd": "Scalable CCD (all pairs)"}


def gpu_method(spec):
    for given, key in GPU_METHODS:
        if spec == given:
            return key
    if spec.startswith("plugin:") and "scalable_ccd" in spec:
        return "scalable-ccd"
    sys.exit("field: gpu: a cell of an unknown method: " + spec)


def gpu_cells(folder, stage):
    """A stage's summaries: its --json, or (a stage cut short) the cells its --out kept."""
    path = os.path.join(folder, stage + ".json")
    if os.path.exists(path):
        return json.load(open(path)), True
    with open(os.path.join(folder, stage + ".results.jsonl")) as f:
        return [c for c in (json.loads(line) for line in f) if c.get("record") == "summary"], False


def gpu_peaks(folder, stage):
    """The most device memory (MiB, nvidia-smi every 100 ms) ccdbench's process and any other (the plugin's
    children) held during the stage."""
    main = int(open(os.path.join(folder, stage + ".pid")).read())
    peaks = {"ccdbench": 0, "plugin": 0}
    for line in open(os.path.join(folder, stage + ".smi")):
        fields = [f.strip() for f in line.split(",")]
        if len(fields) == 2 and fields[0].isdigit() and fields[1].isdigit():
            role = "ccdbench" if int(fields[0]) == main else "plugin"
            peaks[role] = max(peaks[role], int(fields[1]))
    return peaks


def shown_command(command):
    words = shlex.split(command)
    shown = []
    for w in words:
        w = re.sub(r"^/root/out/[a-z]+/gpu/", "OUT/", w)
        w = w.replace("/work/main/device-carry/plugins/", "PLUGINS/").replace("/work/main/device-carry/data/", "$CCDBENCH_DATA_DIR/")
        w = w.replace("/work/main/device-carry/bin/ccdbench", "device-carry/bin/ccdbench")
        shown.append(w)
    return shlex.join(shown)


def gpu(folders):
    rows, stages, meta = [], [], {}
    for folder in folders:
        with open(os.path.join(folder, "gpu.txt")) as f:
            name, driver, memory = [x.strip() for x in f.read().strip().split(",")]
        meta.setdefault("device", "%s (%s), driver %s" % (name, memory, driver))
        with open(os.path.join(folder, "version.txt")) as f:
            meta.setdefault("ccdbench", f.readline().strip())
        order = ["cloth-funnel", "rod-twist", "default", "large"]  # gpu.sh's
        present = {f.split(".")[0] for f in os.listdir(folder) if f.endswith(".smi")}
        for stage in sorted(present, key=lambda n: (order.index(n) if n in order else len(order), n)):
            cells, whole = gpu_cells(folder, stage)
            peaks = gpu_peaks(folder, stage)
            wall = os.path.join(folder, stage + ".wall_ms")
            stages.append({"stage": stage, "whole": whole, "cells": len(cells),
                           "seconds": round(int(open(wall).read()) / 1000.0, 1) if os.path.exists(wall) else None,
                           "device_mib_smi": peaks, "command": shown_command(open(os.path.join(folder, stage + ".command")).read())})
            for c in cells:
                key = gpu_method(c["spec"])
                scene = {"cloth-funnel": "cloth-funnel (public)", "rod-twist": "rod-twist (public)"}.get(stage, c["scene"])
                device = c.get("device_bytes", 0) / 2.0 ** 20 if key != "scalable-ccd" else peaks["plugin"]
                nd = c.get("nondeterministic_at_step")
                rows.append({"stage": stage, "scene": scene, "thickness": number(c["thickness"]), "method": key, "steps": c["steps"],
                             "triangles": c["triangles"], "colliding": c["colliding"], "missed": c["missed"], "false_alarms": c["false_alarms"],
                             "errors": c.get("errors", 0), "toi_checked": c.get("toi_checked", 0), "toi_late": c.get("toi_late", 0),
                             "toi_error_p99": "%.3g" % c["toi_error_p99"] if c.get("toi_checked") else "",
                             "changed_at_step": "" if nd is None else nd, "ms_per_step": "%.4g" % c["ms_per_step"], "device_mib": "%.0f" % device})
    write_csv("gpu.csv", rows, GPU_COLUMNS)
    meta["stages"] = stages
    with open(os.path.join(DATA, "gpu.json"), "w") as f:
        json.dump(meta, f, indent=1, sort_keys=True)
        f.write("\n")
    print("field: GPU data written to " + os.path.relpath(DATA, ROOT))


# ---------------------------------------------------------------------------------------------------------------
# tables: Markdown from the committed data, between <!-- field-table: NAME --> and <!-- /field-table --> markers


def read_csv(name):
    path = os.path.join(DATA, name)
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def read_methods():
    return {m["key"]: m for m in read_csv("methods.csv")}


def markdown(header, rows, align=None):
    align = align or ["---"] + ["---:"] * (len(header) - 1)
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(align) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def short(value):
    """A measured number as the tables print it: 3 significant digits, thousands and above as whole numbers."""
    return ("%.3g" % value) if abs(value) < 1000 else "{:,}".format(int(round(value)))


def us(ns):
    return "-" if ns == "" else short(float(ns) / 1000.0)


def dash(value):
    return "-" if value in ("", None) else value


def order(methods):
    """The tables' order of methods: methods.csv's."""
    return list(methods)


def totals(rows, table, exponent=None):
    return {r["method"]: r for r in rows if r["table"] == table and r["set"] == "all" and (exponent is None or int(r["exponent"]) == exponent)}


def toi_cells(r):
    if int(r["toi_checked"]) == 0:
        return ["-", "-", "-", "-"]
    return ["%s of %s" % (r["toi_late"], r["toi_checked"]), dash(r["toi_error_mean"]), dash(r["toi_error_p99"]), dash(r["toi_error_max"])]


def table_methods(methods, data):
    manifest = {m["library"]: m for m in read_csv("builds.csv")}
    rows = []
    for key, m in methods.items():
        built = manifest.get(m["build"], {})
        rows.append([m["label"], m["library"], m["commit"], m["licence"], m["delta"], m["toi"], m["claims"], m["call"],
                     built.get("patches", "-") if m["build"] not in ("", "-") else "-"])
    return markdown(["method", "library", "commit", "licence", "δ > 0", "TOI", "claims", "called as (defaults)", "patched to build"], rows,
                    ["---"] * 9)


def table_headline(methods, data):
    main = totals(data["queries"], "main")
    stress = {(r["method"], r["thickness"]): r for r in data["stress"]}
    scaled = {}
    for r in data["queries"]:
        if r["table"] == "scale" and r["set"] == "all" and int(r["exponent"]) != 0:
            s = scaled.setdefault(r["method"], [0, 0])
            s[0] += int(r["fn"])
            s[1] += int(r["errors"])
    rows = []
    for key in order(methods):
        if key not in main:
            continue
        r = main[key]
        late = "%s of %s" % (r["toi_late"], r["toi_checked"]) if int(r["toi_checked"]) else "-"
        z, p = stress.get((key, "0")), stress.get((key, "positive"))
        sc = scaled.get(key)
        rows.append([methods[key]["label"], r["queries"], r["fn"], r["fp"], r["errors"], late, dash(r["toi_error_p99"]), us(r["ns_per_query"]),
                     "%d / %d" % (sc[0], sc[1]) if sc else "-", "%s / %s" % (z["fn"], z["errors"]) if z else "-",
                     "%s / %s" % (p["fn"], p["errors"]) if p and methods[key]["delta"].startswith("yes") else "-", methods[key]["licence"]])
    return markdown(["method", "queries", "FN", "FP", "errors", "TOI late", "TOI error p99", "µs/query", "2^k, k ≠ 0: FN / errors",
                     "extremes δ = 0: FN / errors", "extremes δ > 0: FN / errors", "licence"], rows,
                    ["---"] + ["---:"] * 10 + ["---"])


def table_queries(methods, data, table):
    rows = []
    wanted = [r for r in data["queries"] if r["table"] == table and r["set"] != "all"]
    for set_name in SETS:
        for kind in KINDS:
            for key in order(methods):
                for r in wanted:
                    if r["set"] == set_name and r["kind"] == kind and r["method"] == key:
                        rows.append([set_name, kind, methods[key]["label"], r["queries"], r["positives"], r["fn"], r["fp"], r["errors"]] +
                                    toi_cells(r) + [us(r["ns_per_query"])])
    all_rows = totals(data["queries"], table)
    for key in order(methods):
        if key in all_rows:
            r = all_rows[key]
            rows.append(["**all**", "", methods[key]["label"], r["queries"], r["positives"], r["fn"], r["fp"], r["errors"]] + toi_cells(r) +
                        [us(r["ns_per_query"])])
    return markdown(["set", "kind", "method", "queries", "positives", "FN", "FP", "errors", "TOI late", "TOI error mean", "p99", "max",
                     "µs/query"], rows, ["---", "---", "---"] + ["---:"] * 10)


def table_scales(methods, data):
    exponents = sorted({int(r["exponent"]) for r in data["queries"] if r["table"] == "scale"})
    cells = {(int(r["exponent"]), r["method"]): r for r in data["queries"] if r["table"] == "scale" and r["set"] == "all"}
    rows = []
    queries = ""
    for key in order(methods):
        if not any((k, key) in cells for k in exponents):
            continue
        row = [methods[key]["label"]]
        for k in exponents:
            r = cells.get((k, key))
            row.append("%s / %s / %s" % (r["fn"], r["fp"], r["errors"]) if r else "-")
            queries = r["queries"] if r else queries
        rows.append(row)
    return markdown(["method (FN / FP / errors of %s queries)" % queries] + ["2^%d" % k for k in exponents], rows)


def table_stress(methods, data):
    cells = {(r["method"], r["thickness"]): r for r in data["stress"]}
    rows = []
    for key in order(methods):
        z, p = cells.get((key, "0")), cells.get((key, "positive"))
        if not z:
            continue
        positive = "%s / %s / %s" % (p["fn"], p["fp"], p["errors"]) if p and methods[key]["delta"].startswith("yes") else "not asked (no δ)"
        rows.append([methods[key]["label"], "%s / %s / %s" % (z["fn"], z["fp"], z["errors"]), positive])
    z0 = next(iter(r for r in data["stress"] if r["thickness"] == "0"), None)
    p0 = next(iter(r for r in data["stress"] if r["thickness"] == "positive"), None)
    header = ["method", "δ = 0: FN / FP / errors (%s queries, %s positive)" % (z0["queries"], z0["positives"]) if z0 else "δ = 0",
              "δ > 0: FN / FP / errors (%s positive)" % p0["positives"] if p0 else "δ > 0"]
    return markdown(header, rows)


def table_steps(methods, data):
    rows = []
    for r in data["steps"]:
        rows.append([r["scene"], r["thickness"], methods[r["method"]]["label"], r["steps"], short(float(r["tests_per_step"])), r["colliding"],
                     r["missed"], r["false_alarms"], r["errors"], dash(r["toi_late"]), short(float(r["ms_per_step"]))])
    return markdown(["scene", "δ", "method (full's broad phase)", "steps", "tests/step", "colliding", "missed", "false alarms", "errors",
                     "TOI late", "ms/step"], rows, ["---", "---:", "---"] + ["---:"] * 8)


def table_wang(methods, data):
    summed = {}
    for r in data["queries"]:
        if r["table"] == "main" and r["set"] == "handcrafted":
            s = summed.setdefault(r["method"], [0, 0, 0, 0.0])
            s[0] += int(r["queries"])
            s[1] += int(r["fp"])
            s[2] += int(r["fn"])
            s[3] += float(r["ns_per_query"] or 0) * int(r["queries"])
    rows = []
    for w in data["wang"]:
        key = w["method"]
        s = summed.get(key)
        published = "%s / %s / %s" % (dash(w["handcrafted_fp"]), dash(w["handcrafted_fn"]), dash(w["handcrafted_us"]))
        simulation = "%s / %s / %s" % (dash(w["simulation_fp"]), dash(w["simulation_fn"]), dash(w["simulation_us"]))
        mine = "%d / %d / %s (%d queries)" % (s[1], s[2], us(s[3] / s[0]), s[0]) if s and s[0] else "-"
        rows.append([methods[key]["label"] if key in methods else key, published, simulation, mine, w["why"]])
    return markdown(["method", "Wang 2021, handcrafted: FP / FN / µs", "Wang 2021, simulation: FP / FN / µs", "ours, handcrafted sample: FP / FN / µs",
                     "where ours differ, why"], rows, ["---"] * 5)


def table_commands(methods, data):
    run = data["run"]
    return "```sh\n" + "\n".join(run.get("commands", [])) + "\n```"


def table_budget(methods, data):
    run = data["run"]
    rows = [[stage, "%.0f" % seconds] for stage, seconds in run.get("seconds", {}).items()]
    rows.append(["**whole report**", "%.0f (budget %d)" % (sum(run.get("seconds", {}).values()), run.get("budget_seconds", 0))])
    return markdown(["stage", "wall seconds"], rows)


def table_gpu(methods, data):
    rows = []
    for r in data["gpu"]:
        if int(r["colliding"]) == 0:
            continue  # a cell with no colliding pair can miss nothing: not judged here (gpu.csv keeps it)
        late = "%s of %s" % (r["toi_late"], r["toi_checked"]) if int(r["toi_checked"]) else "-"
        changed = "step %s" % r["changed_at_step"] if r["changed_at_step"] != "" else "no"
        rows.append([r["scene"], r["thickness"], GPU_LABELS[r["method"]], r["steps"], "{:,}".format(int(r["triangles"])), r["colliding"], r["missed"],
                     r["false_alarms"], r["errors"], late, dash(r["toi_error_p99"]), changed, short(float(r["ms_per_step"])), r["device_mib"]])
    return markdown(["scene", "δ", "method", "steps", "triangles", "colliding", "missed", "false alarms", "errors", "TOI late", "TOI error p99",
                     "answers changed between passes", "ms/step", "device MiB"], rows, ["---", "---:", "---"] + ["---:"] * 11)


def table_gpucommands(methods, data):
    meta = data["gpumeta"]
    lines = ["# %s; %s" % (meta.get("device", "?"), meta.get("ccdbench", "?"))]
    for s in meta.get("stages", []):
        took = "%.0f s" % s["seconds"] if s["seconds"] is not None else "cut short by the device time limit: %d cells kept" % s["cells"]
        lines.append("# %s (%s; device MiB at most: ccdbench %d, Scalable CCD's child %d)" % (s["stage"], took, s["device_mib_smi"]["ccdbench"],
                                                                                          s["device_mib_smi"]["plugin"]))
        lines.append(s["command"])
    return "```sh\n" + "\n".join(lines) + "\n```"


TABLES = {
    "methods": table_methods,
    "headline": table_headline,
    "queries": lambda m, d: table_queries(m, d, "main"),
    "delta": lambda m, d: table_queries(m, d, "delta"),
    "scales": table_scales,
    "stress": table_stress,
    "steps": table_steps,
    "wang": table_wang,
    "commands": table_commands,
    "budget": table_budget,
    "gpu": table_gpu,
    "gpucommands": table_gpucommands,
}
MARKER = re.compile(r"(<!-- field-table: ([a-z]+) -->\n)(.*?)(<!-- /field-table -->)", re.S)


def render(text, methods, data):
    def replace(match):
        name = match.group(2)
        if name not in TABLES:
            sys.exit("field: unknown table %r" % name)
        return match.group(1) + TABLES[name](methods, data) + "\n" + match.group(4)

    return MARKER.sub(replace, text)


def tables(check):
    methods = read_methods()
    run_path = os.path.join(DATA, "run.json")
    data = {"queries": read_csv("queries.csv"), "stress": read_csv("stress.csv"), "steps": read_csv("steps.csv"), "wang": read_csv("wang2021.csv"),
            "run": json.load(open(run_path)) if os.path.exists(run_path) else {}, "gpu": read_csv("gpu.csv"),
            "gpumeta": json.load(open(os.path.join(DATA, "gpu.json"))) if os.path.exists(os.path.join(DATA, "gpu.json")) else {}}
    differ = []
    expected = {os.path.join(ROOT, "reports", "field", "README.md"): set(TABLES), os.path.join(ROOT, "README.md"): {"headline"}}
    for path, names in expected.items():
        with open(path) as f:
            text = f.read()
        missing = names - {m.group(2) for m in MARKER.finditer(text)}
        if missing:
            sys.exit("field: %s lacks the tables %s (<!-- field-table: NAME --> ... <!-- /field-table -->)" %
                     (os.path.relpath(path, ROOT), ", ".join(sorted(missing))))
        new = render(text, methods, data)
        if new == text:
            continue
        if check:
            old_tables = {m.group(2): m.group(3) for m in MARKER.finditer(text)}
            for m in MARKER.finditer(new):
                if old_tables.get(m.group(2)) != m.group(3):
                    differ.append("%s: table %s" % (os.path.relpath(path, ROOT), m.group(2)))
        else:
            with open(path, "w") as f:
                f.write(new)
            print("field: tables written into " + os.path.relpath(path, ROOT))
    if differ:
        print("field: these tables differ from what reports/field/data/ gives (edit the data, then run scripts/field/field.py tables):")
        for d in differ:
            print("  " + d)
        sys.exit(1)
    if check:
        print("field: every table matches reports/field/data/")


def main(argv):
    if len(argv) >= 1 and argv[0] == "sample" and len(argv) == 4:
        sample(argv[1], argv[2], argv[3])
    elif len(argv) == 3 and argv[0] == "relabel":
        relabel(argv[1], argv[2])
    elif len(argv) == 2 and argv[0] == "collect":
        collect(argv[1])
    elif len(argv) >= 2 and argv[0] == "gpu":
        gpu(argv[1:])
    elif len(argv) >= 1 and argv[0] == "tables" and argv[1:] in ([], ["--check"]):
        tables(argv[1:] == ["--check"])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
