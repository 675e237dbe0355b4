import re, sys, collections
for f in sys.argv[1:]:
    ev = collections.defaultdict(list)
    wall_end = None
    for line in open(f):
        m = re.match(r'\s*(\d+) trace (\d+) (\d+\.\d+) (\S+) ?(.*)', line)
        if m: ev[int(m.group(2))].append((float(m.group(3)), m.group(4), m.group(5).strip()))
    t0 = min(e[0][0] for e in ev.values())
    wall = int(open(f.replace('.log', '.wall')).read())
    print("==", f, "wall", wall)
    for pid, es in sorted(ev.items()):
        tot = collections.Counter()
        last = None; first_item=None
        items = []
        for t, name, what in es:
            if name == 'item-start':
                cur = {'start': t, 'what': what}
                if first_item is None: first_item = t
                if last is not None: tot['between items (dumped->next start)'] += t - last
            elif name == 'loaded': cur['loaded'] = t; tot['load'] += t - cur['start']
            elif name == 'cell-done':
                su, st = map(float, what.split()); cur['own'] = su + st
                tot['own (setup+steps)'] += su + st
                tot['cell rest (loaded->done - own)'] += (t - cur['loaded']) - su - st
                cur['done'] = t
            elif name == 'dumped': tot['dump'] += t - cur['done']; last = t; items.append(cur)
        names = [n for _, n, _ in es]
        tm = {n: t for t, n, _ in es}
        print(" pid %d: main %+.0f, mpi-init %+.0f, first item %+.0f, plan %s, warm-done %+.0f, last dumped %+.0f, finalize %+.0f, finalized %+.0f; items %d" % (
            pid, tm['main'] - t0, tm['mpi-init'] - t0, first_item - t0,
            ("%+.0f..%+.0f" % (tm['plan-start'] - t0, tm['plan-end'] - t0)) if 'plan-start' in tm else '-', tm.get('warm-done', t0) - t0, last - t0,
            tm.get('finalize', t0) - t0, tm.get('finalized', t0) - t0, len(items)))
        for k, v in tot.items(): print("    %-40s %8.0f ms" % (k, v))
        big = sorted(items, key=lambda c: -(c['done'] - c['loaded'] - c['own']))[:5]
        for c in big: print("      rest %.0f load %.0f own %.0f %s" % (c['done'] - c['loaded'] - c['own'], c['loaded'] - c['start'], c['own'], c['what']))
