"""Tests of energy.excitation: the paper's excitation pattern and waypoint command profiles."""

from __future__ import annotations

import numpy as np
import pytest

from energy import CommandProfile, excitation_commands, waypoint_commands
from terrain import DataError, InvalidParameterError, UnknownNameError

_trapezoid = getattr(np, "trapezoid", None) or np.trapz


# ------------------------------------------------------------------ excitation pattern
def test_excitation_uses_the_papers_levels_and_visits_every_combination() -> None:
    p = excitation_commands(160.0, 0.01, seed=4)
    assert len(p) == 16000 and p.dt_s == pytest.approx(0.01)
    speeds = np.round(p.v_mps, 9)
    omegas = np.round(p.omega_radps, 9)
    assert set(np.unique(speeds)) <= {0.0, 0.1, 0.2, 0.3, 0.4}
    assert set(np.unique(omegas)) <= {0.0, 0.35, 0.7, 1.05}
    pairs = set(zip(speeds.tolist(), omegas.tolist()))
    assert len(pairs) == 20  # 5 speeds x 4 yaw rates
    # at rest for the first and last second
    assert np.all(p.v_mps[:100] == 0) and np.all(p.omega_radps[-100:] == 0)
    moving = (p.v_mps != 0) | (p.omega_radps != 0)
    assert 0.8 < moving.mean() < 0.99  # one combination in 20 is (0, 0)


def test_excitation_holds_last_between_min_and_max() -> None:
    p = excitation_commands(60.0, 0.01, hold_s=(2.0, 3.0), rest_s=0.0, seed=1)
    change = np.flatnonzero((np.diff(p.v_mps) != 0) | (np.diff(p.omega_radps) != 0)) + 1
    holds = np.diff(change) * p.dt_s
    # consecutive holds may repeat a combination across a cycle boundary (then they merge)
    assert holds.min() >= 2.0 - 1e-9
    assert np.median(holds) <= 3.0 + 1e-9


def test_excitation_is_seeded() -> None:
    a = excitation_commands(30.0, seed=3)
    b = excitation_commands(30.0, seed=3)
    c = excitation_commands(30.0, seed=4)
    assert np.array_equal(a.v_mps, b.v_mps) and np.array_equal(a.omega_radps, b.omega_radps)
    assert not np.array_equal(a.v_mps, c.v_mps)


def test_excitation_both_signs() -> None:
    p = excitation_commands(120.0, seed=2, omega_sign="both")
    assert p.omega_radps.min() < 0 < p.omega_radps.max()
    assert excitation_commands(120.0, seed=2).omega_radps.min() == 0.0


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"duration_s": -1.0}, InvalidParameterError, "duration_s"),
        ({"duration_s": 2.0, "rest_s": 1.0}, InvalidParameterError, "rest"),
        ({"dt_s": 0.0}, InvalidParameterError, "dt_s"),
        ({"hold_s": (3.0, 1.0)}, InvalidParameterError, "hold_s"),
        ({"speed_levels_mps": (0.1, float("nan"))}, InvalidParameterError, "speed_levels_mps"),
        ({"omega_sign": "negative"}, UnknownNameError, "omega_sign"),
        ({"seed": 1.5}, InvalidParameterError, "seed"),
    ],
)
def test_excitation_bad_input(kwargs: dict, exc: type, match: str) -> None:
    with pytest.raises(exc, match=match):
        excitation_commands(**kwargs)


# ------------------------------------------------------------------ waypoint profiles
def test_straight_segment_trapezoid_closed_form() -> None:
    # 2 m at 0.5 m/s with 0.5 m/s^2: 1 s up, 3 s cruise, 1 s down = 5 s
    p = waypoint_commands([[0.0, 0.0], [2.0, 0.0]], 0.5, accel_mps2=0.5, dt_s=0.001)
    assert p.duration_s == pytest.approx(5.0, abs=1e-3)
    assert p.v_mps.max() == pytest.approx(0.5)
    assert _trapezoid(p.v_mps, p.time_s) == pytest.approx(2.0, abs=1e-5)
    assert p.pose_xyh[-1, :2] == pytest.approx([2.0, 0.0])
    assert p.v_mps[0] == 0.0 and p.v_mps[-1] == 0.0
    assert np.all(p.omega_radps == 0.0)


def test_short_segment_is_triangular() -> None:
    p = waypoint_commands([[0.0, 0.0], [0.1, 0.0]], 1.0, accel_mps2=0.5, dt_s=0.001)
    assert p.v_mps.max() == pytest.approx(np.sqrt(0.1 * 0.5), abs=1e-3)
    assert p.duration_s == pytest.approx(2 * np.sqrt(0.1 / 0.5), abs=2e-3)


def test_turns_in_place_by_the_heading_change() -> None:
    wp = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
    p = waypoint_commands(wp, 0.4, turn_rate_radps=0.5, dt_s=0.001)
    turning = p.omega_radps != 0
    assert np.all(p.v_mps[turning] == 0)  # pivot turns only
    assert _trapezoid(p.omega_radps, p.time_s) == pytest.approx(np.pi, abs=1e-3)  # two left turns
    assert p.omega_radps.max() == pytest.approx(0.5)
    assert p.pose_xyh[-1] == pytest.approx([0.0, 1.0, np.pi])
    # positions follow the commanded speeds
    h = p.pose_xyh[:, 2]
    x = np.concatenate(([0.0], np.cumsum(0.5 * np.diff(p.time_s) * (p.v_mps[1:] * np.cos(h[1:]) + p.v_mps[:-1] * np.cos(h[:-1])))))
    assert np.abs(x - p.pose_xyh[:, 0]).max() < 1e-3


def test_start_heading_adds_a_first_turn() -> None:
    p = waypoint_commands([[0.0, 0.0], [0.0, 1.0]], 0.4, start_heading_rad=0.0, dt_s=0.001)
    assert _trapezoid(p.omega_radps, p.time_s) == pytest.approx(np.pi / 2, abs=1e-3)
    assert p.pose_xyh[0, 2] == pytest.approx(0.0)


@pytest.mark.parametrize(
    ("args", "kwargs", "match"),
    [
        (([[0.0, 0.0]], 0.5), {}, "shape"),
        (([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0]], 0.5), {}, "repeated"),
        (([[0.0, 0.0], [np.nan, 0.0]], 0.5), {}, "finite"),
        (([[0.0, 0.0], [1.0, 0.0]], 0.0), {}, "speed_mps"),
        (([[0.0, 0.0], [1.0, 0.0]], 0.5), {"accel_mps2": -1.0}, "accel_mps2"),
    ],
)
def test_waypoint_bad_input(args: tuple, kwargs: dict, match: str) -> None:
    with pytest.raises(InvalidParameterError, match=match):
        waypoint_commands(*args, **kwargs)


# ------------------------------------------------------------------ CommandProfile
def test_profile_from_poses_recovers_the_commands() -> None:
    p = waypoint_commands([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], 0.4, dt_s=0.005)
    q = CommandProfile.from_poses(p.time_s, p.pose_xyh)
    assert np.abs(q.v_mps - p.v_mps).max() < 0.01
    assert np.abs(q.omega_radps - p.omega_radps).max() < 0.02


def test_profile_validation() -> None:
    with pytest.raises(DataError, match="uniformly spaced"):
        CommandProfile([0.0, 0.1, 0.3], [0.0] * 3, [0.0] * 3)
    with pytest.raises(DataError, match="strictly increasing"):
        CommandProfile([0.0, 0.1, 0.1], [0.0] * 3, [0.0] * 3)
    with pytest.raises(InvalidParameterError, match="length of time_s"):
        CommandProfile([0.0, 0.1, 0.2], [0.0] * 2, [0.0] * 3)
    with pytest.raises(DataError, match="finite"):
        CommandProfile([0.0, 0.1, 0.2], [0.0, np.nan, 0.0], [0.0] * 3)
    with pytest.raises(InvalidParameterError, match="pose_xyh"):
        CommandProfile([0.0, 0.1, 0.2], [0.0] * 3, [0.0] * 3, np.zeros((3, 2)))
