#!/usr/bin/python3
"""Prints the report's H200 table from the JSON summaries of scripts/device-opencl.sh (reports/opencl/device/).
Usage: /usr/bin/python3 reports/opencl/table.py [FOLDER]"""
import json
import os
import sys

folder = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), 'device')
NAMES = {'frames/3036.ply': 'rod-twist 3036→3037', 'frames/227.ply': 'cloth-funnel 227→228'}
FILES = [('rod-twist-1thread.json', 1), ('rod-twist-16threads.json', 16), ('cloth-funnel-1thread.json', 1),
         ('cloth-funnel-16threads.json', 16), ('paper-1thread.json', 1), ('paper-16threads.json', 16)]


def kind(strategy):
    return ('opencl' if 'backend=opencl' in strategy else 'cpu', 'conservative' if 'conservative' in strategy else 'cubic64')


rows = {}
for name, threads in FILES:
    for cell in json.load(open(os.path.join(folder, name))):
        backend, narrow = kind(cell['strategy'])
        rows.setdefault((cell['scene'], narrow), {})[(backend, threads)] = cell
print('| step(s) | narrow phase | CPU, 1 thread | CPU, 16 threads | H200 | H200 vs 16 threads | colliding | missed CPU / H200 '
      '| false alarms CPU / H200 | H200 stages (ms, ≥ 0.05) |')
print('|---|---|---|---|---|---|---|---|---|---|')
for (scene, narrow), cells in sorted(rows.items(), key=lambda item: (item[0][1], item[0][0] not in NAMES, item[0][0])):
    one, cpu, gpu = cells.get(('cpu', 1)), cells.get(('cpu', 16)), cells[('opencl', 16)]
    stages = ', '.join(f'{stage} {ms:.2f}' for stage, ms in gpu['stage_ms'].items() if ms >= 0.05)
    label = NAMES.get(scene, f"{scene}, {gpu['steps']} steps")
    single = f"{one['ms_per_step']:.1f}" + ('' if one['steps'] == gpu['steps'] else f" ({one['steps']} steps)") if one else '-'
    print(f"| {label} | {narrow} | {single} | {cpu['ms_per_step']:.2f} | **{gpu['ms_per_step']:.2f}** | "
          f"{cpu['ms_per_step'] / gpu['ms_per_step']:.1f}x | {gpu['colliding']} | {cpu['missed']} / {gpu['missed']} | "
          f"{cpu['false_alarms']} / {gpu['false_alarms']} | {stages} |")
