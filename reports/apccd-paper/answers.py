#!/usr/bin/python3
"""Every step's answers digest of a map's cells, for verification by parity: OUT/raw/answers.tsv.gz holds scene,
resolved strategy, step and the digest of the pairs and TOI bits the strategy reported (`run` writes it into each step
record of --out's results.jsonl). map.py --parity compares an OpenCL map's digests with those of the CPU map's cells,
which were verified against the exact truth: equal digests at every step are equal collision sets, so equal verdicts.

Usage: answers.py CELLS OUT   (CELLS: the map's --out folder; OUT: the map's folder, holding raw/map.json)"""
import gzip
import json
import os
import sys


def main(cells, out):
    wanted = {(s["scene"], s["strategy"]) for s in json.load(open(os.path.join(out, "raw", "map.json")))}
    digests = {}
    path = os.path.join(cells, "results.jsonl")
    with (gzip.open(path, "rt") if path.endswith(".gz") else open(path)) as results:
        for line in results:
            record = json.loads(line)
            key = (record.get("scene"), record.get("strategy"))
            if record.get("record") == "step" and key in wanted:
                # A cell run again (after an interruption) writes its steps again: the last run's are the cell's.
                digests[key + (record["step"],)] = record["answers"]
    with gzip.open(os.path.join(out, "raw", "answers.tsv.gz"), "wt") as tsv:
        tsv.write("scene\tstrategy\tstep\tanswers\n")
        for (scene, strategy, step), answers in sorted(digests.items()):
            tsv.write(f"{scene}\t{strategy}\t{step}\t{answers}\n")
    print(f"answers: {len(digests)} steps of {len(wanted)} cells into {out}/raw/answers.tsv.gz")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
