#!/usr/bin/python3
"""Prints a table of the report from the JSON summaries of scripts/device-opencl.sh (reports/opencl/device/, the
H200) or of the PoCL runs here (reports/opencl/pocl/, with THREADS 2 and DEVICE PoCL).
Usage: /usr/bin/python3 reports/opencl/table.py [FOLDER [THREADS [DEVICE]]]"""
import json
import os
import sys

folder = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), 'device')
threads_all = int(sys.argv[2]) if len(sys.argv) > 2 else 16
device = sys.argv[3] if len(sys.argv) > 3 else 'H200'
NAMES = {'frames/3036.ply': 'rod-twist 3036→3037', 'frames/227.ply': 'cloth-funnel 227→228'}
FILES = [(f'{name}-1thread.json', 1) for name in ('rod-twist', 'cloth-funnel', 'paper')] + \
        [(f'{name}-{threads_all}threads.json', threads_all) for name in ('rod-twist', 'cloth-funnel', 'paper')]


def kind(strategy):
    return ('opencl' if 'backend=opencl' in strategy else 'cpu', 'conservative' if 'conservative' in strategy else 'cubic64')


rows = {}
for name, threads in FILES:
    if not os.path.exists(os.path.join(folder, name)):
        continue
    for cell in json.load(open(os.path.join(folder, name))):
        backend, narrow = kind(cell['strategy'])
        rows.setdefault((cell['scene'], narrow), {})[(backend, threads)] = cell
print(f'| step(s) | narrow phase | CPU, 1 thread | CPU, {threads_all} threads | {device} | {device} vs {threads_all} threads | colliding '
      f'| missed CPU / {device} | false alarms CPU / {device} | {device} stages (ms, ≥ 0.05) |')
print('|---|---|---|---|---|---|---|---|---|---|')
for (scene, narrow), cells in sorted(rows.items(), key=lambda item: (item[0][1], item[0][0] not in NAMES, item[0][0])):
    one, cpu, gpu = cells.get(('cpu', 1)), cells.get(('cpu', threads_all)), cells[('opencl', threads_all)]
    stages = ', '.join(f'{stage} {ms:.2f}' for stage, ms in gpu['stage_ms'].items() if ms >= 0.05)
    label = NAMES.get(scene, f"{scene}, {gpu['steps']} steps")
    single = f"{one['ms_per_step']:.1f}" + ('' if one['steps'] == gpu['steps'] else f" ({one['steps']} steps)") if one else '-'
    print(f"| {label} | {narrow} | {single} | {cpu['ms_per_step']:.2f} | **{gpu['ms_per_step']:.2f}** | "
          f"{cpu['ms_per_step'] / gpu['ms_per_step']:.1f}x | {gpu['colliding']} | {cpu['missed']} / {gpu['missed']} | "
          f"{cpu['false_alarms']} / {gpu['false_alarms']} | {stages} |")
