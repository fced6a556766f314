"""Tests of energy.diagnosis.regimes: per-sample speed, turning, acceleration, grade, ground and space labels."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy import InteractionLog, LogMeta
from energy.diagnosis.regimes import (
    OFF_MAP_LABEL,
    REGIME_DIMENSIONS,
    STANDSTILL_SPEED_MPS,
    TURN_RATE_RADPS,
    UNKNOWN_LABEL,
    acceleration_labels,
    grade_labels,
    ground_labels,
    motion_grade_rad,
    pivoting,
    regime_labels,
    space_labels,
    speed_labels,
    turning_labels,
)
from energy.logs import rest_samples
from terrain import flat_map, ramp_map
from terrawatt_base.errors import DataError, InvalidParameterError


def make_log(v_mps, omega_radps=None, *, dt_s=0.01, pose_xyh=None, ground=None, ground_label=None) -> InteractionLog:
    v = np.asarray(v_mps, dtype=float)
    n = v.size
    t = np.arange(n) * dt_s
    w = np.zeros(n) if omega_radps is None else np.asarray(omega_radps, dtype=float)
    return InteractionLog(t, v, w, np.ones(n), np.ones(n), t, np.full(n, 9.81), pose_xyh=pose_xyh, ground=ground,
                          meta=LogMeta(ground_label=ground_label))


def test_speed_bins_use_the_magnitude_and_lower_edges_belong_to_the_upper_bin():
    log = make_log([0.0, -0.04, 0.05, 0.2, -0.3, 0.5, 0.99, 1.0, 1.5])
    # the first two are slow but not at rest: the speed changes at 4 m/s^2 there (a start)
    assert speed_labels(log).tolist() == [
        "< 0.05 m/s", "< 0.05 m/s", "0.05-0.25 m/s", "0.05-0.25 m/s", "0.25-0.5 m/s", "0.5-1 m/s", "0.5-1 m/s",
        "> 1 m/s", "> 1 m/s",
    ]


def _blocks(*pairs, n=10, dt_s=0.1):
    """Blocks of ``n`` samples at constant (v, omega)."""
    v = np.concatenate([np.full(n, a) for a, _ in pairs])
    w = np.concatenate([np.full(n, b) for _, b in pairs])
    return make_log(v, w, dt_s=dt_s)


def test_a_pivot_is_its_own_speed_class_apart_from_standstill():
    log = _blocks((0.0, 0.0), (0.0, 0.5), (0.0, 0.0), (0.03, 0.0), (0.2, 0.6), (0.0, -0.1))
    labels = speed_labels(log).tolist()
    assert labels[:9] == ["standstill"] * 9 and labels[9] == "< 0.05 m/s"  # the last still sample starts a turn
    assert labels[10:20] == ["pivot"] * 10
    assert labels[21:29] == ["standstill"] * 8
    assert labels[31:39] == ["< 0.05 m/s"] * 8  # creeping: neither at rest nor pivoting
    assert labels[40:50] == ["0.05-0.25 m/s"] * 10 and labels[50:] == ["pivot"] * 10


def test_standstill_is_the_librarys_rest_and_pivots_are_pivoting():
    log = _blocks((0.0, 0.0), (0.0, 0.5), (0.004, 0.0), (0.03, 0.05), (0.5, 0.0), (0.0, -2.0), (0.0, 0.0))
    rest, pivot = rest_samples(log), pivoting(log.v_mps, log.omega_radps)
    assert rest.sum() > 20 and pivot.sum() == 20 and not np.any(rest & pivot)
    for labels in (speed_labels(log), turning_labels(log)):
        np.testing.assert_array_equal(labels == "standstill", rest)
        np.testing.assert_array_equal(labels == "pivot", pivot)
    assert pivoting(0.0, 0.5) is True and pivoting(0.0, 0.0) is False and pivoting(STANDSTILL_SPEED_MPS, 1.0) is False
    assert pivoting(0.0, TURN_RATE_RADPS) is True


def test_turning_tells_pivot_arc_straight_and_standstill():
    v = [0.0, 0.0, 0.0, 0.0, 0.01, 0.5, 0.5, 0.5, 1.0, -0.5]
    w = [0.0, 0.0, 0.0, 0.5, -0.8, 0.0, 0.05, 0.3, 0.15, -0.4]
    # the third sample is still but a turn starts from it (not at rest): driving straight, slowly
    assert turning_labels(make_log(v, w)).tolist() == [
        "standstill", "standstill", "straight", "pivot", "pivot", "straight", "straight", "arc", "straight", "arc",
    ]


def test_acceleration_labels_of_a_trapezoid_speed_profile():
    t = np.arange(600) * 0.01
    v = np.interp(t, [0.0, 1.0, 3.0, 5.0, 6.0], [0.0, 0.0, 1.0, 1.0, 0.0])  # up at 0.5, down at 1 m/s^2
    labels = acceleration_labels(make_log(v))
    assert set(labels[:50]) == {"steady"}
    assert set(labels[130:270]) == {"accelerating"}
    assert set(labels[330:470]) == {"steady"}
    assert set(labels[530:570]) == {"braking"}
    # reversing: the speed |v| grows, so it is accelerating too
    assert set(acceleration_labels(make_log(-v))[130:270]) == {"accelerating"}


def _pose(x, y, h):
    n = np.broadcast(x, y, h).shape[0]
    return np.column_stack([np.broadcast_to(x, (n,)), np.broadcast_to(y, (n,)), np.broadcast_to(h, (n,))])


def test_grade_follows_the_direction_of_motion_on_a_ramp():
    ramp = ramp_map((20, 20), 1.0, grade=0.1)  # rises along +x
    x = np.linspace(5.0, 10.0, 6)
    up = make_log(np.full(6, 0.5), pose_xyh=_pose(x, 10.0, 0.0))
    assert grade_labels(up, ramp).tolist() == ["uphill"] * 6
    np.testing.assert_allclose(motion_grade_rad(up, ramp), math.atan(0.1))
    facing_down = make_log(np.full(6, 0.5), pose_xyh=_pose(x, 10.0, math.pi))
    assert grade_labels(facing_down, ramp).tolist() == ["downhill"] * 6
    reversing_up_the_slope_backwards = make_log(np.full(6, -0.5), pose_xyh=_pose(x, 10.0, math.pi))
    assert grade_labels(reversing_up_the_slope_backwards, ramp).tolist() == ["uphill"] * 6
    across = make_log(np.full(6, 0.5), pose_xyh=_pose(10.0, x, math.pi / 2))
    assert grade_labels(across, ramp).tolist() == ["level"] * 6
    assert grade_labels(up, flat_map((20, 20))).tolist() == ["level"] * 6


def test_grade_is_unknown_without_poses_or_map_and_off_the_map():
    ramp = ramp_map((20, 20), 1.0, grade=0.1)
    no_pose = make_log(np.full(4, 0.5))
    assert grade_labels(no_pose, ramp).tolist() == [UNKNOWN_LABEL] * 4
    with_pose = make_log(np.full(4, 0.5), pose_xyh=_pose(np.array([5.0, 10.0, 25.0, -1.0]), 10.0, 0.0))
    assert grade_labels(with_pose).tolist() == [UNKNOWN_LABEL] * 4
    assert motion_grade_rad(with_pose, None) is None
    assert grade_labels(with_pose, ramp).tolist() == ["uphill", "uphill", UNKNOWN_LABEL, UNKNOWN_LABEL]


def test_ground_labels_per_sample_then_run_then_unknown():
    assert ground_labels(make_log([0.5] * 3, ground=["snow", "snow", "tiles"])).tolist() == ["snow", "snow", "tiles"]
    assert ground_labels(make_log([0.5] * 3, ground_label="asphalt")).tolist() == ["asphalt"] * 3
    assert ground_labels(make_log([0.5] * 3)).tolist() == [UNKNOWN_LABEL] * 3


def test_space_blocks_of_about_five_metres():
    tmap = flat_map((30, 30), 1.0)
    pose = _pose(np.array([0.5, 4.9, 5.0, 29.9, 31.0]), np.array([0.5, 0.5, 12.0, 29.9, 3.0]), 0.0)
    log = make_log(np.full(5, 0.5), pose_xyh=pose)
    assert space_labels(log, tmap).tolist() == [
        "cells (0-4, 0-4)", "cells (0-4, 0-4)", "cells (10-14, 5-9)", "cells (25-29, 25-29)", OFF_MAP_LABEL,
    ]
    coarse = flat_map((6, 6), 5.0)  # a cell is a block
    assert space_labels(log, coarse).tolist()[:3] == ["cell (0, 0)", "cell (0, 0)", "cell (2, 1)"]
    assert space_labels(log).tolist() == [UNKNOWN_LABEL] * 5
    assert space_labels(make_log(np.full(5, 0.5)), tmap).tolist() == [UNKNOWN_LABEL] * 5


def test_regime_labels_has_every_dimension_and_leaves_the_log_alone():
    v = np.linspace(0.0, 1.0, 50)
    pose = _pose(np.linspace(2.0, 8.0, 50), 3.0, 0.0)
    log = make_log(v, np.full(50, 0.2), pose_xyh=pose, ground_label="grass")
    before = {name: np.array(getattr(log, name)) for name in ("time_s", "v_mps", "omega_radps", "pose_xyh")}
    labels = regime_labels(log, terrain=ramp_map((10, 10), 1.0, grade=-0.2))
    assert tuple(labels) == REGIME_DIMENSIONS
    for dim, arr in labels.items():
        assert arr.shape == (50,) and arr.dtype.kind == "U", dim
        assert not arr.flags.writeable
    assert labels["grade"][-1] == "downhill" and labels["ground"][0] == "grass"
    for name, arr in before.items():
        np.testing.assert_array_equal(getattr(log, name), arr)


def test_bad_input_is_named():
    log = make_log([0.5, 0.5])
    with pytest.raises(InvalidParameterError, match="log must be an InteractionLog, got 'str'"):
        regime_labels("run.csv")
    with pytest.raises(InvalidParameterError, match="terrain must be a TerrainMap or None, got 'ndarray'"):
        regime_labels(log, terrain=np.zeros((3, 3)))
    with pytest.raises(DataError, match="log has 1 drive sample; regimes need at least 2"):
        regime_labels(make_log([0.5]))
