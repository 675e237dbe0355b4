"""Fixtures for the module's tests: the build the module comes from (its ccdbench program writes queries and gates
results as a user's shell would), and a cache of its own per session."""

import os
import pathlib
import subprocess

import pytest

import ccdbench


@pytest.fixture(scope="session")
def build_dir():
    # BUILD/python/ccdbench/__init__.py -> BUILD
    return pathlib.Path(ccdbench.__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def program(build_dir):
    path = build_dir / "bin" / "ccdbench"
    assert path.exists(), f"the ccdbench program beside the module is missing: {path}"
    return path


@pytest.fixture(scope="session", autouse=True)
def own_cache(tmp_path_factory):
    os.environ.setdefault("CCDBENCH_CACHE_DIR", str(tmp_path_factory.mktemp("cache")))


@pytest.fixture(scope="session")
def extremes(program, tmp_path_factory):
    """Query files of subnormal and smallest-normal pairs, labelled exactly (`ccdbench stress --write-queries`)."""
    folder = tmp_path_factory.mktemp("extremes")
    subprocess.run([str(program), "stress", "--family", "subnormal,smallest-normal", "--write-queries", str(folder)], check=True,
                   capture_output=True)
    return folder
