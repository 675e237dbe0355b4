#!/usr/bin/env python3
"""A CCD written in vectorized numpy, audited by ccdbench from Python (docs/python.md).

The method samples the pair's coplanarity function f(t) over the step, finds a root by linear interpolation between
two samples of opposite sign, and tests the primitives there: a common way to write CCD quickly, and wrong in known
ways (two roots between samples, contact within δ without coplanarity, a root interpolated after the true one).
The audit finds each: queries labelled by the exact oracle, then scored exactly as `ccdbench queries` scores a
built-in, then the method run as a strategy on a built-in scene, verified against the exact truth and gated.

Usage: PYTHONPATH=BUILD/python /usr/bin/python3 examples/python/audit_numpy_ccd.py [WORKDIR]
"""

import json
import os
import sys
import tempfile

import numpy as np

import ccdbench

SEED = 20261126
SAMPLES = 8  # coplanarity samples over the step
INSIDE = 1e-9  # how far outside the triangle or the segments a hit may lie (barycentric units)


def sampled_ccd(kind, q, delta):
    """hits and TOIs for the (N, 8, 3) queries q; delta is ignored, as many quick CCDs ignore it."""
    t = np.linspace(0.0, 1.0, SAMPLES + 1)
    x0, x1 = q[:, :4], q[:, 4:]

    def at(times):  # positions at times (T, N) -> (T, N, 4, 3)
        return x0[None] + times[..., None, None] * (x1 - x0)[None]

    def coplanarity(x):
        a, b, c, d = (x[..., i, :] for i in range(4))
        if kind == "vertex-face":  # d: the vertex is x[0]; the face b, c, d
            return np.einsum("...k,...k", np.cross(c - b, d - b), a - b)
        return np.einsum("...k,...k", np.cross(b - a, d - c), c - a)

    f = coplanarity(at(np.broadcast_to(t[:, None], (len(t), len(q)))))
    f0, f1 = f[:-1], f[1:]
    crossing = (f0 * f1 <= 0) & ~((f0 == 0) & (f1 == 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = t[:-1, None] + (t[1] - t[0]) * np.where(f0 != f1, f0 / (f0 - f1), 0.0)
    x = at(tau)
    inside = _vertex_in_face(x) if kind == "vertex-face" else _edges_cross(x)
    hit = crossing & inside
    first = np.where(hit, tau, np.inf).min(axis=0)
    hits = np.isfinite(first)
    return hits, np.where(hits, first, 0.0)


def _vertex_in_face(x):
    p, a, b, c = (x[..., i, :] for i in range(4))
    v0, v1, v2 = b - a, c - a, p - a
    d00, d01, d11 = (np.einsum("...k,...k", u, w) for u, w in ((v0, v0), (v0, v1), (v1, v1)))
    d20, d21 = np.einsum("...k,...k", v2, v0), np.einsum("...k,...k", v2, v1)
    den = d00 * d11 - d01 * d01
    with np.errstate(divide="ignore", invalid="ignore"):
        v = (d11 * d20 - d01 * d21) / den
        w = (d00 * d21 - d01 * d20) / den
    return (v >= -INSIDE) & (w >= -INSIDE) & (v + w <= 1 + INSIDE)


def _edges_cross(x):
    a, b, c, d = (x[..., i, :] for i in range(4))
    u, v, w = b - a, d - c, a - c
    uu, uv, vv = (np.einsum("...k,...k", p, r) for p, r in ((u, u), (u, v), (v, v)))
    uw, vw = np.einsum("...k,...k", u, w), np.einsum("...k,...k", v, w)
    den = uu * vv - uv * uv
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (uv * vw - vv * uw) / den
        r = (uu * vw - uv * uw) / den
    return (s >= -INSIDE) & (s <= 1 + INSIDE) & (r >= -INSIDE) & (r <= 1 + INSIDE)


def random_queries(rng, n):
    """n pairs in the unit box, each primitive moved by up to 0.6 over the step: about a third collide."""
    start = rng.random((n, 4, 3))
    return np.concatenate([start, start + rng.uniform(-0.6, 0.6, (n, 4, 3))], axis=1)


def main(workdir):
    print(f"ccdbench {ccdbench.__version__}; seed {SEED}")
    rng = np.random.default_rng(SEED)
    queries = os.path.join(workdir, "queries")
    for kind in ("vertex-face", "edge-edge"):
        q = random_queries(rng, 2000)
        labels = ccdbench.oracle(kind, q, delta=0.0, toi=False)["collides"]
        ccdbench.write_queries(os.path.join(queries, kind, "random.csv"), q, labels.astype(int))
        print(f"{kind}: {len(q)} queries, {int(labels.sum())} collide (exact oracle)")

    print("\nScored on the queries (as `ccdbench queries --toi`):")
    print(f"{'method':<14} {'FN':>4} {'FP':>4} {'errors':>6} {'TOIs':>5} {'late':>5}")
    totals = [s for s in ccdbench.score(queries, ["conservative", sampled_ccd], toi=True) if s["file"] == "(all)"]
    for name, s in zip(["conservative", "sampled_ccd"], totals):
        print(f"{name:<14} {s['false_negatives']:>4} {s['false_positives']:>4} {s['errors']:>6} {s['toi_checked']:>5} {s['toi_late']:>5}")

    print("\nRun on the built-in scene fold, 10 steps at its own δ, verified against the exact truth:")
    scene = ccdbench.generate_scene("fold")
    results = ccdbench.run(scene, ["full", ("sampled", sampled_ccd)], max_steps=10, out=os.path.join(workdir, "results"))
    for r in results:
        print(f"{r['spec']:<24} colliding {r['colliding']}, missed {r['missed']}, false alarms {r['false_alarms']}, errors {r['errors']}")
    baseline = os.path.join(workdir, "baseline.json")
    with open(baseline, "w") as out:
        json.dump([{"scene": "fold", "strategy": r["spec"], "thickness": "scene", "max_missed": 0} for r in results], out)
    passed, lines = ccdbench.check(baseline, results)
    print("\nThe gate (max_missed 0 for both):")
    print("\n".join(lines))
    print("passed" if passed else "FAILED")
    return 0 if not passed else 1  # the audit is expected to catch the method


if __name__ == "__main__":
    if len(sys.argv) > 1:
        os.makedirs(sys.argv[1], exist_ok=True)
        sys.exit(main(sys.argv[1]))
    with tempfile.TemporaryDirectory() as workdir:
        sys.exit(main(workdir))
