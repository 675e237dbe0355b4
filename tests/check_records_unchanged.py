#!/usr/bin/python3
"""The records test (issue 64): `ccdbench run` over the ci suite writes the same --json and results.jsonl as the
recorded ones, every field the same except what no two runs share. RECORDED_DIR holds run.json.gz and
results.jsonl.gz: one record a line, keys sorted, gzipped (about 25 KB against 520 KB).

Usage: check_records_unchanged.py CCDBENCH RECORDED_DIR            runs CCDBENCH and diffs its outputs with RECORDED_DIR
       check_records_unchanged.py --record CCDBENCH RECORDED_DIR   writes RECORDED_DIR from CCDBENCH's outputs

The run: the ci suite at the scenes' δ and at 0, five strategies (two of them miss pairs, one is judged by triangle
pairs and refused at δ > 0), with --toi and two passes, on 2 threads. What is left out of the comparison, by name,
is in MASKED: a field's value there is replaced by "(masked)", so its presence is still compared. Records are
sorted by scene, δ, strategy, kind and step (results.jsonl orders them by when each cell finished). A masked
field added since the recording (a new time, as setup_ms) is taken as it is: its value would not be compared.

The same command is then run again without --fresh: every cell is kept, and the summaries must be the first run's,
marked resumed and without a speed-up.

The recorded files were written by main as it was before issue 64 (71f1e20, `--record`) and are rewritten only for a
change of behaviour meant as one, which its commit states: a difference is a change of behaviour."""

import gzip
import json
import os
import subprocess
import sys
import tempfile

STRATEGIES = "full,apccd,brute,full+cubic64,fcl"
# Times (each pass's, their medians, means and ratios); memory peaks the OS measures (they depend on the allocator
# and the sanitizer); when a cell finished; provenance (machine, build, revision, executable digest, libraries),
# and what names a cell by the executable digest (its key's digest, its file's stem).
MASKED = {
    "ms", "ms_repeats", "stages", "ms_per_step", "ms_per_step_mean", "unattributed_ms_mean", "ms_per_repeat", "stage_ms",
    "stage_ms_mean", "speedup", "setup_ms", "host_peak_bytes", "child_peak_bytes", "finished_at", "machine", "build_type",
    "git_revision", "executable", "provenance", "cell",
}
# Masked whole, shape and all (the rest keep their shape: a map's names, a list's length).
MASKED_WHOLE = {"provenance"}
# Fields of a cell's key that are provenance.
MASKED_IN_KEY = {"executable"}


def masked_value(value):
    """A time's value masked, its shape kept: a map's names (the stages), a list's length (the passes)."""
    if isinstance(value, dict):
        return {k: "(masked)" for k in value}
    if isinstance(value, list):
        return ["(masked)"] * len(value)
    return "(masked)"


def masked(record):
    out = {}
    for name, value in record.items():
        if name in MASKED_WHOLE:
            out[name] = "(masked)"
        elif name in MASKED:
            out[name] = masked_value(value)
        elif name == "key" and isinstance(value, dict):
            out[name] = {k: ("(masked)" if k in MASKED_IN_KEY else v) for k, v in value.items()}
        else:
            out[name] = value
    return out


def order(record):
    return (record.get("scene", ""), record.get("thickness", 0), record.get("strategy", ""), record.get("record", ""),
            record.get("step", -1))


def run(ccdbench, work, fresh=True, name="run.json"):
    cache = os.path.join(work, "cache")
    env = dict(os.environ, CCDBENCH_CACHE_DIR=cache)
    command = [ccdbench, "--threads", "2", "run", "--suite", "ci", "--strategy", STRATEGIES, "--thickness", "scene,0", "--toi",
               "--repeat", "2"] + (["--fresh"] if fresh else []) + ["--json", os.path.join(work, name), "--out", os.path.join(work, "out")]
    print("records: " + " ".join(command), flush=True)
    done = subprocess.run(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if done.returncode != 0:
        sys.exit("records: the run failed (exit %d):\n%s" % (done.returncode, done.stdout))
    with open(os.path.join(work, name)) as f:
        summaries = [masked(s) for s in json.load(f)]
    with open(os.path.join(work, "out", "results.jsonl")) as f:
        lines = sorted((masked(json.loads(line)) for line in f if line.strip()), key=order)
    return {"run.json": summaries, "results.jsonl": lines}


def first_difference(path, a, b):
    """The first place where a (recorded) and b (now) differ, as PATH: RECORDED != NOW, or None."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            if key not in b:
                return "%s.%s: recorded, missing now" % (path, key)
            if key not in a:
                if key in MASKED and path.count(".") == 0:
                    continue  # a masked measure added since the recording: its value would not be compared anyway
                return "%s.%s: new, not recorded (%s)" % (path, key, json.dumps(b[key])[:200])
            found = first_difference(path + "." + key, a[key], b[key])
            if found:
                return found
        return None
    if isinstance(a, list) and isinstance(b, list):
        for i, (x, y) in enumerate(zip(a, b)):
            found = first_difference("%s[%d]" % (path, i), x, y)
            if found:
                return found
        if len(a) != len(b):
            return "%s: %d entries recorded, %d now" % (path, len(a), len(b))
        return None
    if a != b or type(a) is not type(b):
        return "%s: recorded %s, now %s" % (path, json.dumps(a)[:200], json.dumps(b)[:200])
    return None


def describe(record):
    return "%s / %s at δ %s%s" % (record.get("scene"), record.get("strategy"), record.get("thickness"),
                                  ", step %d" % record["step"] if "step" in record else ", summary")


def main(argv):
    record = argv[1:2] == ["--record"]
    args = argv[2:] if record else argv[1:]
    if len(args) != 2:
        sys.exit(__doc__)
    ccdbench, recorded = args
    with tempfile.TemporaryDirectory() as work:
        now = run(ccdbench, work)
        # The same command again keeps every cell (read back, its spec set, written to --json): the summaries are
        # the first run's, marked resumed and without a speed-up (none between cells of two invocations).
        kept = None if record else run(ccdbench, work, fresh=False, name="kept.json")
    if kept:
        expected = [dict(s, resumed=True, speedup_over=None) for s in now["run.json"]]
        for i, (a, b) in enumerate(zip(expected, kept["run.json"])):
            found = first_difference("", a, b)
            if found:
                print("records: the kept run's summary %d (%s)%s" % (i + 1, describe(a), found))
                return 1
        if len(expected) != len(kept["run.json"]):
            print("records: the kept run has %d summaries, the first %d" % (len(kept["run.json"]), len(expected)))
            return 1
        print("records: a second run kept all %d cells and gave the first run's summaries, resumed" % len(expected))
    if record:
        os.makedirs(recorded, exist_ok=True)
        for name, records in now.items():
            with gzip.open(os.path.join(recorded, name + ".gz"), "wt", encoding="utf-8") as f:
                for r in records:
                    f.write(json.dumps(r, sort_keys=True, ensure_ascii=False) + "\n")
        print("records: wrote %s (%d summaries, %d lines of results.jsonl)" % (recorded, len(now["run.json"]), len(now["results.jsonl"])))
        return 0
    differences = 0
    for name, records in now.items():
        with gzip.open(os.path.join(recorded, name + ".gz"), "rt", encoding="utf-8") as f:
            before = [json.loads(line) for line in f if line.strip()]
        if len(before) != len(records):
            print("records: %s: %d records recorded, %d now" % (name, len(before), len(records)))
            differences += 1
        for i, (a, b) in enumerate(zip(before, records)):
            found = first_difference("", a, b)
            if found:
                differences += 1
                print("records: %s record %d (%s)%s" % (name, i + 1, describe(a), found))
    if differences:
        print("records: %d records differ from the recorded ones in %s" % (differences, recorded))
        return 1
    print("records: --json (%d summaries) and results.jsonl (%d lines) are the recorded ones, every field but the masked"
          % (len(now["run.json"]), len(now["results.jsonl"])))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
