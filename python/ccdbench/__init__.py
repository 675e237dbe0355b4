"""ccdbench from Python: the exact CCD oracle on numpy arrays, query files, methods scored against exact labels,
scenes, and verified runs of strategies, with Python CCD audited as ccdbench audits its own.

Queries are float64 arrays of shape (N, 8, 3) in Tight-Inclusion's vertex order (vertex-face: v_t0, f0_t0, f1_t0,
f2_t0, v_t1, f0_t1, f1_t1, f2_t1; edge-edge: ea0_t0, ea1_t0, eb0_t0, eb1_t0, then the same at t1), motion linear in t
in [0, 1]. Kinds are "vertex-face" and "edge-edge" ("vf", "ee").

A Python method is a callable f(kind, q, delta) -> hits or (hits, tois): q is a read-only (N, 8, 3) copy; hits an
array of N booleans (or 0/1 integers or doubles); tois N doubles in [0, 1] (for the pairs reported), given with every
answer or with none (its first answer decides). It is audited as a plugin is: an exception, None, a wrong shape or
type, a hit that is neither 0 nor 1, a NaN or out-of-range TOI on a hit, TOIs given in one batch and not in another,
or a change of the floating-point environment, the working directory or the C locale (each put back) is an error of
the queries it concerns (a batch that fails is asked again one query at a time), counted apart, never an answer.
KeyboardInterrupt and SystemExit are not errors: they end the call and are raised again from it. Bad input raises
ValueError with ccdbench's FILE:WHERE: REASON text.

Everything returned is plain Python (dicts, lists, numbers, numpy arrays): json and pandas take it as it is.
"""

import json
import re

from . import _ccdbench

__version__ = _ccdbench.version()

QueryFile = _ccdbench.QueryFile
Scene = _ccdbench.Scene

def oracle(kind, queries, delta=0.0, toi=True):
    """The exact answer for each query (an (N, 8, 3) array of doubles, each taken as the rational it is) at
    thickness delta >= 0, on every core with the GIL released.

    Returns a dict of arrays of length N: collides (bool: the closed primitives come within delta for some t in
    [0, 1]); toi_lower, toi_upper (the largest double <= the earliest such t and the smallest double >= it; NaN where
    it does not collide or toi is False); by_filter (decided by the certified floating-point filter)."""
    return _ccdbench.oracle(kind, queries, float(delta), bool(toi))


def read_queries(path):
    """Reads a query file (CSV of rationals, 8 rows a query; its kind from its folder vertex-face/ or edge-edge/, or
    its name *vf.csv / *ee.csv). The QueryFile has path, kind, queries (the doubles nearest the rationals, (N, 8, 3),
    read-only), rationals (N x 8 x 3 strings "p/q"), labels (int8: 1 collides at delta 0, 0 not, -1 unlabelled) and
    exactly_double (whether the doubles are the query exactly: the labels belong to the rationals)."""
    return _ccdbench.read_query_file(str(path))


def oracle_file(file, delta="0", toi=True):
    """The exact answers for every query of a QueryFile (or a path), on its rationals, at thickness delta (a number
    or a rational "p/q"), as oracle() returns them, plus exactly_double per query."""
    if not isinstance(file, QueryFile):
        file = read_queries(file)
    answers = _ccdbench.oracle_file(file, str(delta) if not isinstance(delta, float) else _rational(delta), bool(toi))
    answers["exactly_double"] = file.exactly_double
    return answers


def _rational(value):
    from fractions import Fraction

    f = Fraction(float(value))
    return f"{f.numerator}/{f.denominator}"


def write_queries(path, queries=None, labels=None, rationals=None):
    """Writes a query file (atomically): the queries as an (N, 8, 3) array of doubles (each written as the rational
    it is) or as rationals (N x 8 x 3 strings), with labels (1, 0 or -1 per query; default: -1, unlabelled). The kind
    is the path's (a vertex-face/ or edge-edge/ folder, or a *vf.csv / *ee.csv name)."""
    if (queries is None) == (rationals is None):
        raise ValueError("write_queries: give queries (an array) or rationals, not both")
    if rationals is None:
        import numpy as np

        q = np.asarray(queries, dtype=np.float64)
        if q.ndim != 3 or q.shape[1:] != (8, 3):
            raise ValueError(f"queries must have shape (N, 8, 3), not {q.shape}")
        rationals = [[[_rational(c) for c in row] for row in query] for query in q]
    n = len(rationals)
    labels = [-1] * n if labels is None else [int(x) for x in labels]
    if len(labels) != n:
        raise ValueError(f"write_queries: {len(labels)} labels for {n} queries")
    _ccdbench.write_query_file(str(path), rationals, labels)


_NAME = re.compile(r"[A-Za-z0-9_.-]+")


class _Registered:
    """Registers the callables among `specs` for the length of a call: a callable, or (name, callable), becomes
    callable:NAME (with `head` before it: "full+callable:NAME" in a run). A name given is the method's name in every
    result and baseline entry: it must be a valid name, given once, and is never changed; a callable's own __name__
    is made valid and, where taken, numbered (-2, -3, ...) after every given name is reserved."""

    def __init__(self, specs, batch, head=""):
        if not isinstance(batch, int) or isinstance(batch, bool) or batch < 0:
            raise ValueError(f"batch must be an integer >= 0 (0: a whole step or file at a time), not {batch!r}")
        self.given, self.batch, self.head, self.names = list(specs), batch, head, []

    def _parts(self):
        """(strategy head, given name or None, callable) per callable, None per spec."""
        parts = []
        for spec in self.given:
            if isinstance(spec, str):
                parts.append(None)
                continue
            strategy, name, f = self.head, None, spec
            if isinstance(spec, tuple) and len(spec) == 2:
                name, f = spec
                if not isinstance(name, str):
                    raise ValueError(f"a method's name must be a string, not {name!r}")
                if self.head and name in _ccdbench.strategy_names():
                    strategy, name = name + "+", None  # (strategy, callable): its broad phase, the callable after it
            if not callable(f):
                raise ValueError(f"a method is a spec, a callable, or (name, callable): {spec!r}")
            parts.append((strategy, name, f))
        return parts

    def __enter__(self):
        parts = self._parts()
        given = [p[1] for p in parts if p and p[1] is not None]
        for name in given:
            if not _NAME.fullmatch(name):
                raise ValueError(f"method name {name!r}: use letters, digits, '_', '.' and '-' only (it is part of a spec)")
            if given.count(name) > 1:
                raise ValueError(f"method name {name!r} is given to two callables")
        taken, specs = set(given), []
        try:
            for spec, part in zip(self.given, parts):
                if part is None:
                    specs.append(spec)
                    continue
                strategy, name, f = part
                if name is None:
                    own = getattr(f, "__name__", "method")
                    base = re.sub(r"[^A-Za-z0-9_.-]", "_", own if isinstance(own, str) else "method") or "method"
                    name, k = base, 2
                    while name in taken:
                        name, k = f"{base}-{k}", k + 1
                    taken.add(name)
                _ccdbench.register_method(name, f, self.batch)
                self.names.append(name)
                specs.append(f"{strategy}callable:{name}")
        except BaseException:
            self.__exit__()
            raise
        return specs

    def __exit__(self, *exc):
        for name in self.names:
            _ccdbench.unregister_method(name)
        self.names = []
        return False


def score(paths, methods, delta=0.0, toi=False, repeats=1, batch=10000):
    """Scores methods on query files (paths: files or folders) exactly as `ccdbench queries` scores them: per file,
    then "(all)"; each a dict with queries, reported, errors, positives, false_negatives, false_positives (None where
    nothing is labelled), ns_per_query (median over repeats), and with toi the TOIs checked, those later than the
    exact earliest contact (toi_late) and the error's max, median and 99th percentile.

    methods: built-in specs ("conservative", "cubic64:eta=1e-6", "exact", "plugin:PATH", "answers:FILE"), Python
    callables f(kind, q, delta) (called with `batch` queries at a time; named callable:NAME by their __name__), or
    (name, callable)."""
    if isinstance(paths, (str, bytes)) or not hasattr(paths, "__iter__"):
        paths = [paths]
    with _Registered(methods, batch) as specs:
        return _ccdbench.score_queries([str(p) for p in paths], specs, float(delta), bool(toi), int(repeats))


def builtin_scenes():
    """The built-in procedural scenes: name, description and parameters with their defaults."""
    return _ccdbench.builtin_scenes()


def generate_scene(name, **parameters):
    """Built-in scene `name` with these parameters (the others at their defaults), generated into ccdbench's cache
    (CCDBENCH_CACHE_DIR) or read from it. A Scene has label, file, num_vertices, faces ((M, 3) uint32), num_frames,
    thickness and frame(k) ((V, 3) float64)."""
    return _ccdbench.generate_scene(name, {k: float(v) for k, v in parameters.items()})


def load_scene(path):
    """Reads a scene file (or a folder holding scene.json)."""
    return _ccdbench.load_scene(str(path))


def strategy_names():
    return _ccdbench.strategy_names()


def validate_strategy(spec):
    """Checks a strategy spec (NAME[+NARROW][:key=value...]); raises ValueError naming what is wrong."""
    _ccdbench.validate_strategy(spec)


def run(scenes, strategies=("full",), thickness=None, verify=True, toi=False, repeats=1, max_steps=0, out="ccdbench-results"):
    """Runs every strategy over every step of every scene, verified against the exact truth, and returns one dict
    per cell (scene x strategy x thickness) as `ccdbench run --json` writes it (missed, false_alarms, errors,
    toi_late, ms_per_step, provenance, ...). Results are also kept under `out` (results.jsonl), as `run --out`.

    strategies: specs ("full", "apccd", "full+cubic64", "full+plugin:PATH"), or a Python callable f(kind, q, delta):
    run as `full+callable:NAME`, full's broad phase giving it each step's candidate pairs (one call per step and
    kind, on one thread); or (strategy, callable) for another strategy's broad phase. thickness: None (each scene's
    own), a number, or a list of them (None among them: the scene's)."""
    if isinstance(scenes, Scene):
        scenes = [scenes]
    if isinstance(strategies, str) or callable(strategies):
        strategies = [strategies]
    if thickness is None or isinstance(thickness, (int, float)):
        thickness = [thickness]
    thicknesses = [None if t is None else float(t) for t in thickness]
    with _Registered(strategies, 0, head="full+") as specs:
        records = _ccdbench.run(list(scenes), specs, thicknesses, bool(verify), bool(toi), int(repeats), int(max_steps), str(out))
    return [json.loads(r) for r in records]


def write_baseline(baseline, results, margin=0):
    """Writes the gate's baseline of run() results to the file `baseline` (as `ccdbench check --write-baseline`):
    one entry per result, allowing `margin` more missed pairs, errors and late TOIs (a count, or "P%"). Refuses
    (ValueError) what check would fail whatever the entry. Returns the entries written, as dicts."""
    lines = _ccdbench.write_baseline(str(baseline), [json.dumps(r) for r in results], str(margin))
    return [json.loads(line) for line in lines if line.startswith("{")]


def check(baseline, results):
    """The gate's verdict on run() results against a baseline file (as `ccdbench check --baseline`): (passed, lines)."""
    return _ccdbench.check(str(baseline), [json.dumps(r) for r in results])
