"""Shared fixtures: small maps whose answers are known exactly (flat, ramp, wall); process ids of a finished and of a
running process (saves killed long ago, or in progress elsewhere)."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

import terrain

# the benchmarks' experiment scaffolding (e.g. the diagnosis's withheld-effect scenarios) serves
# the tests as known-answer cases: importable as top-level modules, as the benchmark scripts import them
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

from known_models import corridor_map, known_model  # noqa: E402, F401  (fixtures of the planner and CLI tests)

#: Grade (dz/dx) of the ``ramp_map`` fixture.
RAMP_GRADE = 0.1


@pytest.fixture
def flat_map() -> terrain.TerrainMap:
    """20 x 30 cells of 0.5 m (15 m east x 10 m north, origin (0, 0)), elevation 0,
    all asphalt (class 0), no obstacles."""
    return terrain.flat_map((20, 30), 0.5, ground="asphalt")


@pytest.fixture
def ramp_grade() -> float:
    """The grade of the ``ramp_map`` fixture (0.1: rises 0.1 m per metre along +x)."""
    return RAMP_GRADE


@pytest.fixture
def ramp_map() -> terrain.TerrainMap:
    """20 x 40 cells of 0.5 m (20 m east x 10 m north, origin (0, 0)) rising with grade
    0.1 along +x (``z = 0.1 * x`` at cell centres), all asphalt (class 0), no obstacles."""
    return terrain.ramp_map((20, 40), 0.5, grade=RAMP_GRADE, axis="x", ground="asphalt")


@pytest.fixture
def wall_map() -> terrain.TerrainMap:
    """40 x 40 flat cells of 1 m, all asphalt, with an obstacle wall along column 20
    (x in [20, 21) m) open only at rows 30-33 (y in [30, 34) m)."""
    return terrain.wall_map((40, 40), 1.0, wall_col=20, gap_rows=(30, 34), ground="asphalt")


@pytest.fixture
def dead_pid() -> int:
    """The pid of a process that has finished (and been reaped): a save killed long ago."""
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


@pytest.fixture
def live_pid() -> Iterator[int]:
    """The pid of a process that is still running: a save in progress elsewhere."""
    proc = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        yield proc.pid
    finally:
        proc.kill()
        proc.wait()
