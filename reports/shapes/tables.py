#!/usr/bin/python3
"""Prints the tables of reports/shapes/README.md from what reports/shapes/run.sh wrote (the summary records of each
scene's results.jsonl, or results.jsonl.gz).
Usage: /usr/bin/python3 reports/shapes/tables.py [RESULTS]   (default reports/shapes/results)"""

import gzip
import json
import pathlib
import sys

here = pathlib.Path(__file__).resolve().parent
results = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else here / "results"
OBSTACLE = {"spinning-ball": "ball", "drape": "table", "pile": "ground"}


def mib(x):
    return f"{x / 2**20:.2f}"


def obstacle_counts(summary, obstacle):
    """Colliding pairs and faces in contact between the cloth(s) and the obstacle, summed over cloths and steps."""
    pairs = sum(v for k, v in summary.get("colliding_by_objects", {}).items() if k.endswith("/" + obstacle))
    faces = sum(v for k, v in summary.get("faces_in_contact_by_objects", {}).items() if k.endswith("/" + obstacle))
    return pairs, faces


print("| scene | obstacles | strategy | ms/step | scene MiB/frame | strategy MiB (max) | colliding pairs with the obstacle | cloth faces in contact with it | colliding (all) | missed |")
print("|---|---|---|---|---|---|---|---|---|---|")
contact = {}
for scene in ("spinning-ball", "drape", "pile"):
    path = results / scene / "results.jsonl"
    if not path.exists():
        path = results / scene / "results.jsonl.gz"
    if not path.exists():
        continue
    text = gzip.decompress(path.read_bytes()).decode() if path.suffix == ".gz" else path.read_text()
    records = [json.loads(line) for line in text.splitlines()]
    for s in [r for r in records if r.get("record") == "summary"]:
        obstacles = "shape" if s["scene"].endswith("-shape") else "mesh"
        strategy = s["strategy"].split("+")[0]
        # One frame's positions and the faces (24 bytes a vertex, 12 a face): what the scene holds per frame.
        scene_bytes = 24 * s["vertices"] + 12 * s["triangles"]
        pairs, faces = obstacle_counts(s, OBSTACLE[scene])
        contact[(scene, obstacles)] = (pairs, faces, s["steps"])
        print(f"| {scene} | {obstacles} | {strategy} | {s['ms_per_step']:.2f} | {mib(scene_bytes)} | {mib(s.get('kept_bytes', s['history_bytes']))} | "
              f"{pairs} | {faces} | {s['colliding']} | {s['missed']} |")
print()
print("| scene | obstacle | faces in contact, mesh | faces in contact, shape | shape − mesh | steps |")
print("|---|---|---|---|---|---|")
for scene in ("spinning-ball", "drape", "pile"):
    if (scene, "mesh") in contact and (scene, "shape") in contact:
        mesh, shape = contact[(scene, "mesh")], contact[(scene, "shape")]
        print(f"| {scene} | {OBSTACLE[scene]} | {mesh[1]} | {shape[1]} | {shape[1] - mesh[1]:+d} | {mesh[2]} |")
