"""Shared fixtures: the bundled meshes (tests/data of the repository) and the command line.

Tests that compare against the ``meshpyr`` command line run the binary named by the
``MESHPYR_CLI`` environment variable, else ``target/release/meshpyr`` or
``target/debug/meshpyr`` of this checkout; without one they are skipped, saying so.
"""

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import meshpyr

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"


def data(name):
    """Path of a bundled mesh."""
    return DATA / name


def find_cli():
    """The meshpyr binary to compare against, or None."""
    named = os.environ.get("MESHPYR_CLI")
    if named:
        return Path(named)
    for profile in ("release", "debug"):
        candidate = REPO / "target" / profile / "meshpyr"
        if candidate.is_file():
            return candidate
    found = shutil.which("meshpyr")
    return Path(found) if found else None


def cli_runner():
    """A function that runs the meshpyr binary quietly with its arguments and returns the
    finished process; skips the test when there is no binary."""
    binary = find_cli()
    if binary is None or not binary.is_file():
        pytest.skip(
            "no meshpyr binary: build it with `cargo build --release` (or set MESHPYR_CLI) "
            "to compare the bindings with the command line"
        )

    def run(*args):
        return subprocess.run(
            [str(binary), "--quiet", *map(str, args)],
            capture_output=True,
            text=True,
            check=False,
        )

    return run


@pytest.fixture(scope="session")
def cli():
    """Runs the meshpyr command line: ``cli("filter", a, "-o", b)``; returns stdout."""
    run = cli_runner()

    def succeed(*args):
        done = run(*args)
        if done.returncode != 0:
            raise AssertionError(f"meshpyr {' '.join(map(str, args))} failed: {done.stderr}")
        return done.stdout

    return succeed


@pytest.fixture(scope="session")
def cli_error():
    """Runs the meshpyr command line expecting it to fail: ``cli_error("smooth", ...)``;
    returns its stderr."""
    run = cli_runner()

    def fail(*args):
        done = run(*args)
        if done.returncode == 0:
            raise AssertionError(f"meshpyr {' '.join(map(str, args))} succeeded")
        return done.stderr

    return fail


@pytest.fixture(scope="session")
def sphere():
    """A 926-vertex closed sphere with high-valence poles (float32 PLY)."""
    return meshpyr.read(data("sphere_highval.ply"))


@pytest.fixture(scope="session")
def sphere_pyramid(sphere):
    return meshpyr.Pyramid(*sphere)


@pytest.fixture()
def double_ply(tmp_path):
    """Writes (V, F) as a PLY with double positions, so the command line reads the very
    float64 values the bindings get."""

    def make(v, f, name="input.ply"):
        path = tmp_path / name
        meshpyr.write(path, v, f)
        return path

    return make


def assert_same_bits(a, b):
    """Equal arrays, bit for bit (NaN-free float64)."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape
    assert a.dtype == b.dtype
    assert a.tobytes() == b.tobytes(), f"max difference {np.max(np.abs(a - b))}"
