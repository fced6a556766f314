"""Tests of energy.profiles: stop-turn-go waypoint profiles and the mission's drive profile."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy import drive_profile
from energy.profiles import (
    DEFAULT_ACCEL_MPS2,
    DEFAULT_YAW_ACCEL_RADPS2,
    drivable_waypoints,
    move_duration_s,
    planned_durations_s,
    waypoint_commands,
)
from terrain import InvalidParameterError

_trapezoid = getattr(np, "trapezoid", None) or np.trapz


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


# ------------------------------------------------------------------ drive profile (a mission's motion)
def test_drive_profile_drops_repeated_waypoints_and_matches_waypoint_commands() -> None:
    wp = [[0.0, 0.0], [0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 1.0]]
    p = drive_profile(wp, 0.5, turn_rate_radps=0.5, dt_s=0.01)
    q = waypoint_commands([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0]], 0.5, turn_rate_radps=0.5, dt_s=0.01,
                          accel_mps2=DEFAULT_ACCEL_MPS2, yaw_accel_radps2=DEFAULT_YAW_ACCEL_RADPS2)
    assert np.array_equal(p.time_s, q.time_s) and np.array_equal(p.v_mps, q.v_mps)
    assert np.array_equal(p.pose_xyh, q.pose_xyh)
    assert p.pose_xyh[-1, :2] == pytest.approx([2.0, 1.0])


def test_a_stop_survives_the_collinear_rule() -> None:
    """A waypoint named in ``stops`` is stopped at though the heading does not change there (a tour's site): the
    straight splits in two, one ramp down and up (speed / accel) longer; repeated waypoints map a stop onto the kept
    copy."""
    wp = [[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [3.0, 0.0]]
    through = drive_profile(wp, 0.5, turn_rate_radps=0.5, dt_s=0.01)
    stopped = drive_profile(wp, 0.5, turn_rate_radps=0.5, dt_s=0.01, stops=[1])
    assert stopped.duration_s - through.duration_s == pytest.approx(0.5 / DEFAULT_ACCEL_MPS2, abs=0.011)
    at = np.flatnonzero(np.isclose(stopped.pose_xyh[:, 0], 1.0, atol=1e-9))
    assert at.size and np.all(stopped.v_mps[at] == 0.0) and np.all(through.v_mps[1:-1] > 0.0)  # at rest only where stopped
    pts, kept = drivable_waypoints(wp, stops=[1])
    assert pts.tolist() == [[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]] and kept.tolist() == [0, 2]
    assert drivable_waypoints(wp, stops=[0, 3])[1].tolist() == [0]  # the ends are stops anyway
    with pytest.raises(InvalidParameterError, match="stops must be indices of the 4 waypoints"):
        drivable_waypoints(wp, stops=[4])
    with pytest.raises(InvalidParameterError, match="stops must be indices"):
        waypoint_commands([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]], 0.5, stops=[0.5])


def test_drive_profile_is_exported_from_energy() -> None:
    import energy.profiles

    assert "drive_profile" in energy.__all__  # the package's surface; the rest in its module
    for name in ("drive_profile", "DEFAULT_ACCEL_MPS2", "DEFAULT_YAW_ACCEL_RADPS2", "drivable_waypoints",
                 "planned_durations_s"):
        assert name in energy.profiles.__all__
    assert (DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2) == (0.5, 1.0)


def test_planned_durations_match_the_sampled_profile() -> None:
    wp = [[0.0, 0.0], [3.0, 0.0], [3.0, 0.2], [1.0, 0.2]]
    pts, kept = drivable_waypoints(wp)
    assert kept.tolist() == [0, 1, 2]
    turn_s, straight_s = planned_durations_s(pts, None, 0.4, 0.5, 0.5, 1.0)
    p = drive_profile(wp, 0.4, turn_rate_radps=0.5, dt_s=0.001, accel_mps2=0.5, yaw_accel_radps2=1.0)
    assert turn_s[0] == 0.0 and turn_s[1] == pytest.approx(move_duration_s(np.pi / 2, 0.5, 1.0))
    assert float(turn_s.sum() + straight_s.sum()) == pytest.approx(p.duration_s, abs=2e-3)


@pytest.mark.parametrize(
    ("wp", "match"),
    [
        ([[1.0, 1.0], [1.0, 1.0]], "no segment of positive length"),
        ([[0.0, 0.0]], "shape"),
        ([[0.0, 0.0], [np.inf, 0.0]], "finite"),
        ("ab", "numeric"),
    ],
)
def test_drive_profile_bad_waypoints(wp: object, match: str) -> None:
    with pytest.raises(InvalidParameterError, match=match):
        drive_profile(wp, 0.5, turn_rate_radps=0.5, dt_s=0.01)


def test_drive_profile_string_speed_names_the_parameter() -> None:
    with pytest.raises(InvalidParameterError, match="speed_mps must be a real number, got 'fast'"):
        drive_profile([[0.0, 0.0], [1.0, 0.0]], "fast", turn_rate_radps=0.5, dt_s=0.01)


# ------------------------------------------------------------------ collinear waypoints, the pivot alone
def test_a_collinear_waypoint_is_driven_through_and_a_real_turn_is_not() -> None:
    from energy.profiles import COLLINEAR_TOL_RAD

    straight = waypoint_commands([[0.0, 0.0], [6.0, 0.0]], 0.5, dt_s=0.01)
    through = waypoint_commands([[0.0, 0.0], [2.0, 0.0], [3.5, 0.0], [6.0, 0.0]], 0.5, dt_s=0.01)
    np.testing.assert_array_equal(through.v_mps, straight.v_mps)  # one straight from rest to rest: no stop
    np.testing.assert_allclose(through.pose_xyh, straight.pose_xyh, atol=1e-12)
    kink = 100.0 * COLLINEAR_TOL_RAD  # 0.1 mrad: a real turn, a stop and a pivot
    bent = waypoint_commands([[0.0, 0.0], [3.0, 0.0], [6.0, 3.0 * math.tan(kink)]], 0.5, dt_s=0.01)
    assert bent.duration_s > straight.duration_s + 1.0  # stops, pivots, starts again
    pts, kept = drivable_waypoints([[0.0, 0.0], [2.0, 0.0], [2.0, 0.0], [3.5, 0.0], [3.5, 2.0]])
    assert pts.tolist() == [[0.0, 0.0], [3.5, 0.0], [3.5, 2.0]] and kept.tolist() == [0, 3]
    turn, straight_s = planned_durations_s(pts, None, 0.5, 0.5, 0.5, 1.0)
    assert turn[0] == 0.0 and turn[1] > 0.0 and straight_s[0] == pytest.approx(3.5 / 0.5 + 1.0)


def test_the_pivot_alone_is_the_pivot_of_a_stop_turn_go_profile() -> None:
    from energy.profiles import pivot_commands

    p = pivot_commands(math.pi / 2, turn_rate_radps=0.5, yaw_accel_radps2=1.0, dt_s=0.001)
    route = waypoint_commands([[0.0, 0.0], [0.0, 1.0]], 0.5, turn_rate_radps=0.5, yaw_accel_radps2=1.0, dt_s=0.001,
                              start_heading_rad=0.0)
    n = p.time_s.size - 1  # the route's pivot ends where its straight starts
    np.testing.assert_allclose(p.omega_radps[:n], route.omega_radps[:n], atol=1e-12)
    assert np.all(p.v_mps == 0.0) and p.pose_xyh[-1, 2] == pytest.approx(math.pi / 2)
    assert p.duration_s == pytest.approx(math.pi / 2 / 0.5 + 0.5, abs=1e-3)
    with pytest.raises(InvalidParameterError, match="angle_rad"):
        pivot_commands(4.0, turn_rate_radps=0.5)
