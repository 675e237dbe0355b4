"""The Python module: the oracle on arrays and on query files' rationals, query files, Python methods scored and
run as strategies exactly as ccdbench's own, and the callable treated as untrusted code."""

import ctypes
import itertools
import locale
import os
from fractions import Fraction
import json
import pathlib
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

import ccdbench

ROOT = pathlib.Path(__file__).resolve().parents[2]
SEED = 20261126


def crossing_pair():
    """A vertex that passes through a triangle at t = 1/2, and one that stops short of it."""
    q = np.zeros((2, 8, 3))
    triangle = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    for i in range(2):
        q[i, 1:4] = triangle
        q[i, 5:8] = triangle
        q[i, 0] = [0.2, 0.2, 1.0]
    q[0, 4] = [0.2, 0.2, -1.0]
    q[1, 4] = [0.2, 0.2, 0.5]
    return q


def test_version_is_the_programs(program):
    assert re.fullmatch(r"\d+\.\d+\.\d+", ccdbench.__version__)
    printed = subprocess.run([str(program), "--version"], capture_output=True, text=True, check=True).stdout
    assert f"ccdbench {ccdbench.__version__}" in printed


def test_the_oracle_answers_and_brackets_the_earliest_contact():
    answers = ccdbench.oracle("vertex-face", crossing_pair())
    assert answers["collides"].tolist() == [True, False]
    assert answers["toi_lower"][0] == 0.5 and answers["toi_upper"][0] == 0.5
    assert np.isnan(answers["toi_lower"][1])
    # Within δ = 0.6 the second vertex touches too, at its start (it starts 1 away and ends 0.5 away: t = 0.8).
    thick = ccdbench.oracle("vf", crossing_pair(), delta=0.6)
    assert thick["collides"].tolist() == [True, True]
    assert thick["toi_lower"][1] <= 0.8 <= thick["toi_upper"][1]


def test_the_oracle_on_arrays_agrees_with_the_files_labels(extremes):
    checked = 0
    for path in sorted(extremes.rglob("*.csv")):
        file = ccdbench.read_queries(path)
        on_rationals = ccdbench.oracle_file(file)
        labelled = file.labels >= 0
        assert labelled.any()
        assert (on_rationals["collides"][labelled] == (file.labels[labelled] == 1)).all(), path
        on_arrays = ccdbench.oracle(file.kind, file.queries)
        exact = file.exactly_double
        assert (on_arrays["collides"][exact] == on_rationals["collides"][exact]).all(), path
        both = exact & on_rationals["collides"]
        assert (on_arrays["toi_lower"][both] == on_rationals["toi_lower"][both]).all()
        checked += int(labelled.sum())
    assert checked > 50


def test_bad_input_is_a_value_error_naming_it(tmp_path):
    with pytest.raises(ValueError, match=r"shape \(N, 8, 3\)"):
        ccdbench.oracle("vf", np.zeros((3, 8, 2)))
    bad = crossing_pair()
    bad[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match="pair 1"):
        ccdbench.oracle("vf", bad)
    with pytest.raises(ValueError, match="thickness"):
        ccdbench.oracle("vf", crossing_pair(), delta=-1)
    with pytest.raises(ValueError, match="kind"):
        ccdbench.oracle("face-face", crossing_pair())
    broken = tmp_path / "vertex-face" / "broken.csv"
    broken.parent.mkdir()
    broken.write_text("1,2\n")
    with pytest.raises(ValueError, match=r"broken\.csv:"):
        ccdbench.read_queries(broken)
    with pytest.raises(ValueError):
        ccdbench.validate_strategy("full:nope=1")


def test_query_files_round_trip(tmp_path):
    q = crossing_pair()
    path = tmp_path / "vertex-face" / "two.csv"
    ccdbench.write_queries(path, q, [1, 0])
    read = ccdbench.read_queries(path)
    assert read.kind == "vertex-face" and len(read) == 2
    assert (read.queries == q).all() and read.exactly_double.all()
    assert read.labels.tolist() == [1, 0]
    # Each double written as the rational it is: 0.2 is not 1/5.
    assert read.rationals[0][0] == [f"{Fraction(0.2).numerator}/{Fraction(0.2).denominator}"] * 2 + ["1"]
    with pytest.raises(ValueError):
        read.queries[0, 0, 0] = 7.0  # read-only
    again = tmp_path / "vertex-face" / "again.csv"
    ccdbench.write_queries(again, rationals=read.rationals, labels=read.labels)
    assert ccdbench.read_queries(again).rationals == read.rationals


def never(kind, q, delta):
    return np.zeros(len(q), dtype=bool)


def test_a_python_method_that_misses_is_caught_beside_a_built_in(extremes):
    scores = ccdbench.score(extremes, ["conservative", never], toi=True)
    totals = {s["method"].split(":")[0] + (":" + s["method"].split(":")[1] if s["method"].startswith("callable") else ""): s
              for s in scores if s["file"] == "(all)"}
    assert totals["conservative"]["false_negatives"] == 0
    assert totals["conservative"]["toi_late"] == 0
    assert totals["callable:never"]["positives"] > 0
    assert totals["callable:never"]["false_negatives"] == totals["callable:never"]["positives"]
    assert totals["callable:never"]["errors"] == 0


def late(kind, q, delta):
    """Reports every pair that collides, one ulp after the exact earliest contact: every TOI late."""
    answers = ccdbench.oracle(kind, q, delta)
    hits = answers["collides"]
    return hits, np.where(hits, np.nextafter(answers["toi_upper"], 2.0), 0.0).clip(0, 1)


def test_late_tois_are_counted_exactly(extremes):
    (total,) = [s for s in ccdbench.score(extremes, [late], toi=True) if s["file"] == "(all)"]
    assert total["false_negatives"] == 0
    assert total["toi_checked"] > 0
    assert total["toi_late"] == total["toi_checked"]


def raises(kind, q, delta):
    raise RuntimeError("this method is broken")


def returns_none(kind, q, delta):
    return None


def wrong_shape(kind, q, delta):
    return np.zeros((len(q), 2))


def nan_toi(kind, q, delta):
    return np.ones(len(q), dtype=bool), np.full(len(q), np.nan)


def writes_its_input(kind, q, delta):
    q[:, 0, 0] = 0.0
    return np.ones(len(q), dtype=bool)


def changes_rounding(kind, q, delta):
    libm = ctypes.CDLL("libm.so.6")
    libm.fesetround(0x800)  # FE_UPWARD on x86-64: left changed on return
    return np.zeros(len(q), dtype=bool)


def fails_on_the_first(kind, q, delta):
    """Raises whenever the batch holds the file's first query: only that query is an error."""
    if any((row == FIRST).all() for row in q):
        raise ValueError("the first query")
    return np.zeros(len(q), dtype=bool)


FIRST = None


@pytest.mark.parametrize("method", [raises, returns_none, wrong_shape, nan_toi, writes_its_input, changes_rounding])
def test_a_broken_method_gets_errors_and_changes_no_other_answer(extremes, method):
    clean = [s for s in ccdbench.score(extremes, ["conservative", "exact"], toi=True) if s["file"] == "(all)"]
    scores = [s for s in ccdbench.score(extremes, ["conservative", method, "exact"], toi=True) if s["file"] == "(all)"]
    broken = scores[1]
    assert broken["method"].startswith(f"callable:{method.__name__}")
    # Every query is an error of the method (nan_toi: every reported pair; the others: every query), never an answer.
    if method is nan_toi:
        assert broken["errors"] == broken["queries"] and broken["reported"] == 0
    else:
        assert broken["errors"] == broken["queries"]
    for before, after in zip(clean, [scores[0], scores[2]]):
        for field in ("reported", "false_negatives", "false_positives", "toi_checked", "toi_late", "toi_error_max"):
            assert before[field] == after[field], (method.__name__, field)


def test_an_error_lands_on_the_query_that_causes_it(extremes):
    global FIRST
    path = sorted(extremes.rglob("*.csv"))[0]
    file = ccdbench.read_queries(path)
    FIRST = file.queries[0]
    same = int(sum((row == FIRST).all() for row in file.queries))
    (total,) = [s for s in ccdbench.score(path, [fails_on_the_first]) if s["file"] == "(all)"]
    assert len(file) > 1 and total["errors"] == same
    assert total["queries"] == len(file)


def test_a_python_strategy_is_verified_and_gated(program, tmp_path):
    calls = []

    def counting_never(kind, q, delta):
        calls.append((kind, q.shape))
        return np.zeros(len(q), dtype=bool)

    scene = ccdbench.generate_scene("fold")
    results = ccdbench.run(scene, ["full", ("never", counting_never)], max_steps=3, out=tmp_path / "out")
    full, python = results
    assert python["spec"] == "full+callable:never"
    assert full["colliding"] > 0 and full["missed"] == 0
    assert python["missed"] == python["colliding"] > 0
    # Once per step and kind, in each of the two passes (the timed one and the audit's), with the candidate pairs.
    assert len(calls) == 3 * 2 * 2
    assert all(shape[1:] == (8, 3) for _, shape in calls)
    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps(results))  # plain Python: json takes it as it is
    baseline = tmp_path / "baseline.json"
    baseline.write_text(json.dumps([{"scene": "fold", "strategy": r["spec"], "thickness": "scene", "max_missed": 0} for r in results]))
    passed, lines = ccdbench.check(baseline, results)
    assert not passed and lines[1].startswith("FAIL fold / full+callable:never")
    gate = subprocess.run([str(program), "check", "--baseline", str(baseline), str(summary)], capture_output=True, text=True)
    assert gate.returncode == 1, gate.stdout + gate.stderr
    # Its cell is never kept: a changed method is run again, not read back.
    again = ccdbench.run(scene, [("never", lambda kind, q, delta: np.ones(len(q), dtype=bool))], max_steps=3, out=tmp_path / "out")
    assert again[0]["missed"] == 0 and again[0]["false_alarms"] > 0
    # A baseline written from Python gates the same results through check, and the command line's check reads it.
    written = tmp_path / "written.json"
    entries = ccdbench.write_baseline(written, results)
    assert [e["strategy"] for e in entries] == ["full", "full+callable:never"]
    assert entries[1]["max_missed"] == python["missed"] and entries[1]["colliding"] == python["colliding"]
    passed, lines = ccdbench.check(written, results)
    assert passed, lines
    gate = subprocess.run([str(program), "check", "--baseline", str(written), str(summary)], capture_output=True, text=True)
    assert gate.returncode == 0, gate.stdout + gate.stderr
    worse = [dict(r) for r in results]
    worse[0]["missed"] = 1
    assert not ccdbench.check(written, worse)[0]
    unverified = [dict(results[0], verified=False)]
    with pytest.raises(ValueError, match="not verified"):
        ccdbench.write_baseline(tmp_path / "refused.json", unverified)


def test_scenes_as_arrays(tmp_path):
    names = [s["name"] for s in ccdbench.builtin_scenes()]
    assert "fold" in names
    scene = ccdbench.generate_scene("fold")
    assert scene.faces.shape[1] == 3 and scene.faces.max() < scene.num_vertices
    assert scene.frame(0).shape == (scene.num_vertices, 3)
    assert scene.num_frames > 1 and scene.thickness > 0
    with pytest.raises(IndexError):
        scene.frame(scene.num_frames)
    loaded = ccdbench.load_scene(scene.file)
    assert loaded.num_vertices == scene.num_vertices and (loaded.frame(1) == scene.frame(1)).all()


def test_the_example_prints_what_the_docs_show(tmp_path):
    page = (ROOT / "docs" / "python.md").read_text()
    shown = re.search(r"```text\n(ccdbench \d.*?)```", page, re.S).group(1)
    printed = subprocess.run([sys.executable, str(ROOT / "examples" / "python" / "audit_numpy_ccd.py"), str(tmp_path)], capture_output=True,
                             text=True)
    assert printed.returncode == 0, printed.stderr
    assert printed.stdout == shown


def test_installed_it_imports_as_the_docs_say(build_dir, tmp_path):
    cmake = shutil.which("cmake")
    assert cmake, "cmake is needed to install"
    subprocess.run([cmake, "--install", str(build_dir), "--prefix", str(tmp_path)], check=True, capture_output=True)
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": str(tmp_path / "lib" / "python3" / "dist-packages")}
    printed = subprocess.run(["/usr/bin/python3", "-c", "import ccdbench; print(ccdbench.__version__, ccdbench.__file__)"], env=env, cwd=tmp_path,
                             capture_output=True, text=True)
    assert printed.returncode == 0, printed.stderr
    version, where = printed.stdout.split()
    assert version == ccdbench.__version__ and where.startswith(str(tmp_path))


# What an adversarial review found (each failed before its fix): a callable's change of the process is its error and
# is put back, TOIs cannot be left out where they would be late, names given are kept or refused, answers of other
# types are errors, nondeterminism is counted, and a user's interrupt ends the call.


def changes_directory(kind, q, delta):
    os.chdir("/")
    return np.zeros(len(q), dtype=bool)


def changes_locale(kind, q, delta):
    locale.setlocale(locale.LC_ALL, "C.UTF-8")
    return np.zeros(len(q), dtype=bool)


@pytest.mark.parametrize("method", [changes_directory, changes_locale])
def test_a_change_of_the_process_is_put_back_and_is_the_calls_error(extremes, method):
    cwd, before = os.getcwd(), locale.setlocale(locale.LC_ALL)
    if method is changes_locale and before == "C.UTF-8":
        locale.setlocale(locale.LC_ALL, "C")
        before = locale.setlocale(locale.LC_ALL)
    clean = [s for s in ccdbench.score(extremes, ["conservative"]) if s["file"] == "(all)"][0]
    scores = [s for s in ccdbench.score(extremes, [method, "conservative"]) if s["file"] == "(all)"]
    assert scores[0]["errors"] == scores[0]["queries"]
    assert scores[1]["false_negatives"] == clean["false_negatives"] and scores[1]["reported"] == clean["reported"]
    assert os.getcwd() == cwd and locale.setlocale(locale.LC_ALL) == before


def hides_late_tois(kind, q, delta):
    """TOIs one ulp late, left out of every batch that has a hit: its late TOIs would go uncounted."""
    hits, tois = late(kind, q, delta)
    return hits if hits.any() else (hits, tois)


def test_tois_left_out_where_they_would_be_late_are_errors(extremes):
    (total,) = [s for s in ccdbench.score(extremes, [hides_late_tois], toi=True, batch=1) if s["file"] == "(all)"]
    # Its first answer decides: with TOIs (no hit), every hit after it, without, is an error; without (a hit),
    # every answer after it that comes with TOIs is.
    assert total["errors"] > 0 and total["errors"] in (total["positives"], total["queries"] - total["positives"])


def test_names_given_are_kept_or_refused(tmp_path):
    def x(kind, q, delta):
        return np.zeros(len(q), dtype=bool)

    def y(kind, q, delta):
        return np.zeros(len(q), dtype=bool)

    y.__name__ = "x"
    scene = ccdbench.generate_scene("fold")
    results = ccdbench.run(scene, [x, y, ("x-2", x)], max_steps=1, out=tmp_path / "out")
    assert [r["spec"] for r in results] == ["full+callable:x", "full+callable:x-3", "full+callable:x-2"]
    for bad in [[("a:b", x)], [("same", x), ("same", y)], [(3, x)]]:
        with pytest.raises(ValueError):
            ccdbench.score([], bad)
    with pytest.raises(ValueError):
        ccdbench.score([], [x], batch=-1)


def complex_hits(kind, q, delta):
    return np.zeros(len(q)) + 0j


def string_hits(kind, q, delta):
    return np.array(["0"] * len(q))


def masked_hits(kind, q, delta):
    return np.ma.masked_all(len(q), dtype=bool)


@pytest.mark.parametrize("method", [complex_hits, string_hits, masked_hits])
def test_answers_of_other_types_are_errors(extremes, method):
    (total,) = [s for s in ccdbench.score(extremes, [method]) if s["file"] == "(all)"]
    assert total["errors"] == total["queries"]


def test_answers_that_change_between_passes_are_counted(extremes):
    calls = itertools.count()

    def flips(kind, q, delta):
        return np.full(len(q), next(calls) % 2 == 0)

    (total,) = [s for s in ccdbench.score(extremes, [flips], repeats=2) if s["file"] == "(all)"]
    assert total["changed_between_passes"] == total["queries"]


@pytest.mark.parametrize("interrupt", [KeyboardInterrupt, SystemExit])
def test_a_users_interrupt_ends_the_call(extremes, interrupt, tmp_path):
    def stops(kind, q, delta):
        raise interrupt()

    with pytest.raises(interrupt):
        ccdbench.score(extremes, ["conservative", stops])
    with pytest.raises(interrupt):
        ccdbench.run(ccdbench.generate_scene("fold"), ["full", stops], max_steps=2, out=tmp_path / "out")
    # Nothing is left registered: the same name is free again.
    (total,) = [s for s in ccdbench.score(extremes, [("stops", never)]) if s["file"] == "(all)"]
    assert total["errors"] == 0
