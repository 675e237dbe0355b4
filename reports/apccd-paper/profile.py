#!/usr/bin/python3
"""apccd's stages before and after, from scripts/apccd-profile.sh's runs (OUT/raw/{before,after}-ROUND.json): profile.md,
for every scene and strategy the median over the rounds of each build's mean ms per step and of each stage's, and the
speed-ups over full that follow (each build's cells against its own full, same round).

Usage: profile.py OUT"""
import glob
import json
import os
import re
import statistics
import sys
from collections import defaultdict

# A stage is listed when it takes at least this share of the strategy's step in either build.
STAGE_SHARE_SHOWN = 0.05
ORDER = ["full+cubic64", "apccd+cubic64", "apccd+cubic64:heuristic=boxes", "full", "apccd"]
SCENES = ["spinning-ball", "drape", "flag", "twist", "funnel", "pile"]


def short(strategy):
    """The spec as typed (its backend kept): full+cubic64, apccd, apccd+cubic64:heuristic=boxes, ..."""
    family = strategy.split("+")[0].split(":")[0]
    narrow = "+cubic64" if "+cubic64" in strategy else ""
    extra = ":heuristic=boxes" if ":heuristic=boxes" in strategy else ""
    backend = ":backend=opencl" if "backend=opencl" in strategy else ""
    return family + narrow + extra + backend


def main(out):
    runs = defaultdict(list)  # (variant, scene, strategy) -> summaries over rounds
    meta = {}
    for path in sorted(glob.glob(os.path.join(out, "raw", "*-*.json"))):
        variant = os.path.basename(path).split("-")[0]
        for s in json.load(open(path)):
            scene = s["scene"][:-5] if s["scene"].endswith(".json") else s["scene"]
            runs[(variant, scene, short(s["strategy"]))].append(s)
            meta[variant] = s
    run = dict(line.rstrip("\n").split("\t") for line in open(os.path.join(out, "raw", "run.tsv")))
    answers = dict(zip(*[line.rstrip("\n").split("\t") for line in open(os.path.join(out, "raw", "answers.tsv"))]))
    med = statistics.median

    def ms(variant, scene, strategy):
        cells = runs.get((variant, scene, strategy))
        return med([c["ms_per_step_mean"] for c in cells]) if cells else None

    def stages(variant, scene, strategy):
        cells = runs.get((variant, scene, strategy), [])
        names = {stage for c in cells for stage in c["stage_ms_mean"]}
        return {stage: med([c["stage_ms_mean"].get(stage, 0.0) for c in cells]) for stage in names}

    def scene_key(scene):
        m = re.match(r"(.+)-r(\d+)-spf(\d+)$", scene)
        return (SCENES.index(m.group(1)) if m and m.group(1) in SCENES else 99, int(m.group(3)) if m else 0, scene)

    scenes = sorted({scene for _, scene, _ in runs}, key=scene_key)
    strategies = sorted({strategy for _, _, strategy in runs},
                        key=lambda s: (s.endswith("opencl"), ORDER.index(s.replace(":backend=opencl", "")) if s.replace(":backend=opencl", "") in ORDER else 99))
    lines = ["# apccd's stages before and after (issue 37)\n",
             open(os.path.join(out, "raw", "command.txt")).read().replace("# ", "    # ").replace("\nccdbench", "\n    ccdbench") + "\n",
             f"Machine: {meta['after'].get('machine', '?')}, {meta['after'].get('threads', '?')} threads. Before: revision "
             f"{meta['before'].get('git_revision', '?')}; after: revision {meta['after'].get('git_revision', '?')}. "
             f"{run['rounds']} rounds, each build in turn, {run['elapsed_s']} s in all. Every number is the median over the rounds of "
             "a cell's mean ms per step (or of one stage's). Answers: "
             f"{answers['differing_steps']} of {answers['compared_steps']} steps differ between the builds (every step's "
             "digest of reported pairs and TOI bits, first round).\n",
             "## Speed-ups over full, each build against its own full\n",
             "full's ms per step over the strategy's (above 1: faster than full), before -> after.\n"]
    header = ["scene"] + [s for s in strategies if not s.startswith("full")]
    lines += ["| " + " | ".join(header) + " |", "|---|" + "---:|" * (len(header) - 1)]
    for scene in scenes:
        row = [scene]
        for strategy in header[1:]:
            base = "full+cubic64" if "+cubic64" in strategy else "full"
            if strategy.endswith(":backend=opencl"):
                base += ":backend=opencl"
            entries = []
            for variant in ("before", "after"):
                a, f = ms(variant, scene, strategy), ms(variant, scene, base)
                entries.append(f"{f / a:.2f}x" if a and f else "-")
            row.append(" -> ".join(entries))
        lines.append("| " + " | ".join(row) + " |")
    lines += ["", "## Every cell, stage by stage\n",
              f"Mean ms per step before -> after, and each stage that takes at least {100 * STAGE_SHARE_SHOWN:.0f}% of the "
              "step in either build (ms before -> after).\n",
              "| scene | strategy | before | after | after / before | stages |", "|---|---|---:|---:|---:|---|"]
    for scene in scenes:
        for strategy in strategies:
            before, after = ms("before", scene, strategy), ms("after", scene, strategy)
            if after is None and before is None:
                continue
            sb, sa = stages("before", scene, strategy), stages("after", scene, strategy)
            shown = sorted((stage for stage in set(sb) | set(sa)
                            if (before and sb.get(stage, 0) >= STAGE_SHARE_SHOWN * before) or (after and sa.get(stage, 0) >= STAGE_SHARE_SHOWN * after)),
                           key=lambda stage: -max(sb.get(stage, 0), sa.get(stage, 0)))
            text = ", ".join(f"{stage} {sb.get(stage, 0):.2f} -> {sa.get(stage, 0):.2f}" if before else f"{stage} {sa.get(stage, 0):.2f}" for stage in shown)
            ratio = f"{after / before:.2f}" if before and after else "-"
            lines.append(f"| {scene} | {strategy} | {before:.2f} | {after:.2f} | {ratio} | {text} |" if before else
                         f"| {scene} | {strategy} | - | {after:.2f} | - | {text} |")
    open(os.path.join(out, "profile.md"), "w").write("\n".join(lines) + "\n")
    print(f"profile: {len(scenes)} scenes, {len(strategies)} strategies; answers: {answers['differing_steps']} of {answers['compared_steps']} steps differ")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
