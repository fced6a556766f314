"""Tests of energy.logs.slope: the pitch under a run's poses on a map."""

import dataclasses

import numpy as np
import pytest

from energy import InteractionLog, LogMeta
from energy.logs import log_slope_rad
from terrain.procedural import flat_map, ramp_map
from terrawatt_base.errors import DataError, InvalidParameterError, OutOfBoundsError


def _log(x, y, heading):
    n = len(x)
    t = np.arange(n) * 0.1
    ta = np.arange(0.0, t[-1] + 0.005, 0.01)
    return InteractionLog(t, np.full(n, 0.5), np.zeros(n), np.ones(n), np.ones(n), ta, np.full(ta.size, 9.81),
                          meta=LogMeta(source="slope-test"), pose_xyh=np.column_stack([x, y, heading]))


def test_the_pitch_is_the_grade_along_the_heading():
    tmap = ramp_map((40, 40), 1.0, grade=0.1, axis="x")
    x = np.linspace(5.0, 30.0, 6)
    y = np.full(6, 20.0)
    headings = np.array([0.0, np.pi / 2, np.pi, -np.pi / 2, np.pi / 4, np.pi / 3])
    got = log_slope_rad(tmap, _log(x, y, headings))
    np.testing.assert_allclose(got, np.arctan(0.1 * np.cos(headings)), atol=1e-12)
    assert got[0] > 0 and got[2] < 0  # uphill forwards, downhill backwards along x


def test_level_ground_reads_zero():
    tmap = flat_map((20, 20), 1.0)
    got = log_slope_rad(tmap, _log(np.linspace(2.0, 15.0, 5), np.full(5, 3.0), np.full(5, 0.7)))
    np.testing.assert_array_equal(got, np.zeros(5))


def test_bad_inputs_are_refused():
    tmap = ramp_map((20, 20), 1.0)
    log = _log(np.linspace(2.0, 15.0, 5), np.full(5, 3.0), np.zeros(5))
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap"):
        log_slope_rad("map.npz", log)
    with pytest.raises(DataError, match="needs its poses"):
        log_slope_rad(tmap, dataclasses.replace(log, pose_xyh=None))
    with pytest.raises(OutOfBoundsError):
        log_slope_rad(tmap, _log(np.linspace(2.0, 95.0, 5), np.full(5, 3.0), np.zeros(5)))
