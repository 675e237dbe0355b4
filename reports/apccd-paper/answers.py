#!/usr/bin/python3
"""Every step's answers digest of a map's cells, for verification by parity: OUT/raw/answers.tsv.gz holds each cell of
map.json (its unique name), its scene's content digest and δ (from the cell's key), the step and the digest of the pairs
and TOI bits the strategy reported (`run` writes it into each step record of --out's results.jsonl). map.py --parity compares an OpenCL map's digests with those of the CPU map's cells,
which were verified against the exact truth: equal digests at every step are equal collision sets, so equal verdicts.

Usage: answers.py CELLS OUT   (CELLS: the map's --out folder; OUT: the map's folder, holding raw/map.json)"""
import gzip
import json
import os
import sys


def main(cells, out):
    # The cells map.json holds, by their unique names: a folder of cells may hold others of the same scene label and
    # strategy (another profile, another build), whose steps must not be taken for these.
    summaries = {s["cell"]: s for s in json.load(open(os.path.join(out, "raw", "map.json")))}
    digests = {}
    steps = []
    path = os.path.join(cells, "results.jsonl")
    with (gzip.open(path, "rt") if path.endswith(".gz") else open(path)) as results:
        for line in results:
            record = json.loads(line)
            if record.get("record") == "step":
                steps.append(record)
                continue
            # A cell's step records come just before its summary.
            if record.get("record") == "summary" and record.get("cell") in summaries:
                digests[record["cell"]] = {step["step"]: step["answers"] for step in steps
                                           if (step["scene"], step["strategy"]) == (record["scene"], record["strategy"])}
            steps = []
    with gzip.open(os.path.join(out, "raw", "answers.tsv.gz"), "wt") as tsv:
        tsv.write("cell\tscene_content\tthickness\tstep\tanswers\n")
        for cell, by_step in sorted(digests.items()):
            key = summaries[cell]["key"]
            for step, answers in sorted(by_step.items()):
                tsv.write(f"{cell}\t{key['scene_content']}\t{key['thickness']!r}\t{step}\t{answers}\n")
    missing = len(summaries) - len(digests)
    print(f"answers: {sum(len(d) for d in digests.values())} steps of {len(digests)} cells into {out}/raw/answers.tsv.gz"
          + (f"; {missing} cells of map.json have no step records in {path}" if missing else ""))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
