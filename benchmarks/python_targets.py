#!/usr/bin/env python3
"""The Python module's two targets, measured in one invocation on one machine (issue "Python"):

1. the exact oracle from Python on query files' rationals (oracle_file, labels only) against
   `ccdbench queries --method exact` on the same files: both as time inside the decision (the program's ns per query
   times queries; the module's oracle_file calls), and as wall time of the whole command / script part;
2. the module's own overhead per query when a Python callable is scored in batches of 10,000: the ns per query of a
   callable that returns at once (what ccdbench adds around the callable, the callable's own return included).

Usage: PYTHONPATH=build/release/python /usr/bin/python3 benchmarks/python_targets.py [QUERY_FOLDER...]
       (default: the public data's query files, found as scripts/data-dir.sh finds them)
"""

import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import ccdbench

ROOT = pathlib.Path(__file__).resolve().parents[1]
PROGRAM = pathlib.Path(ccdbench.__file__).resolve().parents[2] / "bin" / "ccdbench"


def folders():
    if len(sys.argv) > 1:
        return [pathlib.Path(p) for p in sys.argv[1:]]
    data = os.environ.get("CCDBENCH_DATA_DIR") or subprocess.run(["bash", "-c", "source scripts/data-dir.sh; echo ${CCDBENCH_DATA_DIR:-}"], cwd=ROOT,
                                                                  capture_output=True, text=True).stdout.strip()
    if not data:
        sys.exit("python_targets: no query folder given and no public data found (scripts/fetch-data.sh)")
    return [pathlib.Path(data) / "sample-queries", pathlib.Path(data) / "scalable-ccd-sample"]


def main():
    paths = folders()
    files = sorted(p for folder in paths for p in folder.rglob("*.csv") if p.parent.name in ("vertex-face", "edge-edge", "queries"))
    print(f"ccdbench {ccdbench.__version__}; {len(files)} query files under {', '.join(map(str, paths))}; {os.cpu_count()} cores")

    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        subprocess.run([str(PROGRAM), "queries", *map(str, paths), "--method", "exact", "--json", f"{tmp}/q.json"], check=True, capture_output=True)
        program_wall = time.perf_counter() - start
        scores = json.load(open(f"{tmp}/q.json"))
        rows = scores["scores"] if isinstance(scores, dict) else scores
        total = [r for r in rows if r["file"] == "(all)"][0]
    program_inside = total["ns_per_query"] * total["queries"] / 1e9

    start = time.perf_counter()
    read = [ccdbench.read_queries(f) for f in files]
    read_time = time.perf_counter() - start
    start = time.perf_counter()
    answers = [ccdbench.oracle_file(f, toi=False) for f in read]
    module_inside = time.perf_counter() - start
    queries = sum(len(f) for f in read)
    wrong = sum(int(((a["collides"] != (f.labels == 1)) & (f.labels >= 0)).sum()) for a, f in zip(answers, read))
    print(f"\n1. exact oracle on {queries} queries' rationals (labels only), against their labels: {wrong} differ")
    print(f"   ccdbench queries --method exact: {program_inside:.3f} s deciding ({total['ns_per_query']:.0f} ns/query), {program_wall:.3f} s wall")
    print(f"   ccdbench.oracle_file:            {module_inside:.3f} s deciding, {read_time + module_inside:.3f} s with reading the files")
    print(f"   module / program: {module_inside / program_inside:.2f}x deciding, {(read_time + module_inside) / program_wall:.2f}x wall")

    def at_once(kind, q, delta):
        return np.zeros(len(q), dtype=bool)

    print("\n2. a callable that returns at once, scored in batches of 10,000 (median of 5 repeats per file):")
    (noop,) = [s for s in ccdbench.score(paths, [at_once], repeats=5, batch=10000) if s["file"] == "(all)"]
    print(f"   {noop['queries']} queries: {noop['ns_per_query']:.0f} ns per query (target: at most 1000)")


if __name__ == "__main__":
    main()
