"""How long the robot takes to drive a route: the stop-turn-go profile's closed form, the one rule for a route's time.

The robot drives a route stop-turn-go (:mod:`energy.profiles`): it starts from rest, stops at
every waypoint where the heading changes, pivots there with a ramped yaw rate, drives each
straight from rest to rest with a ramped speed, and drives through a waypoint where the heading
does not change (:data:`energy.profiles.COLLINEAR_TOL_RAD`). Its time is therefore not
``length / speed + sum(angles) / turn_rate``: every stop-and-go adds ``speed / accel`` (1 s at
0.5 m/s and 0.5 m/s^2) and every pivot ``turn_rate / yaw_accel`` (0.5 s at 0.5 rad/s and
1 rad/s^2), more where a straight or a pivot is too short to reach its cruise rate.
:func:`route_duration_s` is that time in closed form (:func:`energy.profiles.planned_durations_s`
over :func:`energy.profiles.drivable_waypoints`, on the horizontal length the profile drives):
what a route reports (:attr:`planner.Route.duration_s`), a tour's legs are timed by and the
mission simulator's log lasts (to a sample). :func:`waypoint_times_s` gives the time the robot
leaves each waypoint on the same clock.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from energy.profiles import DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2, drivable_waypoints, planned_durations_s
from terrawatt_base.checks import check_optional_real, check_real

__all__ = ["route_duration_s", "waypoint_times_s"]


def _standing(waypoints_m: Any) -> bool:
    """Whether the waypoints are one point repeated (a route whose start is its goal: it takes no time)."""
    try:
        wp = np.asarray(waypoints_m, dtype=np.float64)
    except (TypeError, ValueError):
        return False  # drivable_waypoints says what is wrong
    return wp.ndim == 2 and wp.shape[1:] == (2,) and len(wp) >= 2 and bool(np.all(np.isfinite(wp))) and bool(
        np.all(wp == wp[0]))


def _clock(waypoints_m: Any, speed_mps: float, turn_rate_radps: float, start_heading_rad: float | None,
           accel_mps2: float, yaw_accel_radps2: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The drivable points, their route indices, and the clock: ``clock[2m]`` the end of the pivot that starts driven
    segment ``m``, ``clock[2m + 1]`` the end of its straight (s); the straights' durations."""
    speed = check_real("speed_mps", speed_mps, low=0.0, low_inclusive=False)
    rate = check_real("turn_rate_radps", turn_rate_radps, low=0.0, low_inclusive=False)
    accel = check_real("accel_mps2", accel_mps2, low=0.0, low_inclusive=False)
    yaw_accel = check_real("yaw_accel_radps2", yaw_accel_radps2, low=0.0, low_inclusive=False)
    heading = check_optional_real("start_heading_rad", start_heading_rad)
    pts, kept = drivable_waypoints(waypoints_m)  # checks the waypoints
    turn_s, straight_s = planned_durations_s(pts, heading, speed, accel, rate, yaw_accel)
    return pts, kept, np.cumsum(np.column_stack([turn_s, straight_s]).ravel()), straight_s


def route_duration_s(waypoints_m: Any, speed_mps: float, turn_rate_radps: float, *,
                     start_heading_rad: float | None = None, accel_mps2: float = DEFAULT_ACCEL_MPS2,
                     yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2) -> float:
    """The time (s) the robot takes to drive ``waypoints_m`` stop-turn-go, from rest to rest.

    Parameters
    ----------
    waypoints_m : array_like, shape (K, 2)
        The route (m); repeated waypoints are dropped and collinear ones driven through.
    speed_mps, turn_rate_radps : float
        Cruise speed (m/s) and pivot yaw rate (rad/s), > 0.
    start_heading_rad : float, optional
        The heading the robot starts on (a pivot to the first segment first); ``None``: facing it.
    accel_mps2, yaw_accel_radps2 : float
        The profile's acceleration limits (m/s^2, rad/s^2; default the profile's and the turn tables').

    Returns
    -------
    float
        Pivots plus straights, each ramped from and to rest; 0 for one point repeated (start equals goal).

    Raises
    ------
    InvalidParameterError
        Not a finite (K >= 2, 2) array; non-positive speeds, rates or accelerations.

    Examples
    --------
    >>> route_duration_s([[0, 0], [1, 0], [2, 0]], 0.5, 0.5)  # 2 m at 0.5 m/s plus 1 s of ramps
    5.0
    >>> round(route_duration_s([[0, 0], [2, 0], [2, 2]], 0.5, 0.5), 4)  # two straights, a quarter turn
    13.6416
    """
    if _standing(waypoints_m):
        return 0.0
    return float(_clock(waypoints_m, speed_mps, turn_rate_radps, start_heading_rad, accel_mps2,
                        yaw_accel_radps2)[2][-1])


def waypoint_times_s(waypoints_m: Any, speed_mps: float, turn_rate_radps: float, *,
                     start_heading_rad: float | None = None, accel_mps2: float = DEFAULT_ACCEL_MPS2,
                     yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2) -> np.ndarray:
    """The time (s) the robot leaves each waypoint of ``waypoints_m`` driven stop-turn-go (the last: its arrival).

    At a waypoint where it turns, the end of its pivot there; at one it drives through, the time it
    passes it on the straight's ramped profile; at the last, :func:`route_duration_s`.

    Parameters
    ----------
    waypoints_m, speed_mps, turn_rate_radps, start_heading_rad, accel_mps2, yaw_accel_radps2
        As :func:`route_duration_s`.

    Returns
    -------
    ndarray, shape (K,)
        Non-decreasing; a repeated waypoint has its neighbour's time.

    Raises
    ------
    InvalidParameterError
        As :func:`route_duration_s`.

    Examples
    --------
    >>> waypoint_times_s([[0, 0], [1, 0], [2, 0], [2, 2]], 0.5, 0.5).round(4).tolist()
    [0.0, 2.5, 8.6416, 13.6416]
    """
    if _standing(waypoints_m):
        return np.zeros(len(waypoints_m))
    accel = check_real("accel_mps2", accel_mps2, low=0.0, low_inclusive=False)
    pts, kept, clock, straight_s = _clock(waypoints_m, speed_mps, turn_rate_radps, start_heading_rad, accel,
                                          yaw_accel_radps2)
    wp = np.asarray(waypoints_m, dtype=np.float64)
    along = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(wp, axis=0).T))))
    seg = np.clip(np.searchsorted(kept, np.arange(wp.shape[0]), side="right") - 1, 0, len(kept) - 1)
    length = np.hypot(*np.diff(pts, axis=0).T)[seg]
    s = np.clip(along - along[kept[seg]], 0.0, length)
    peak = np.minimum(float(speed_mps), np.sqrt(length * accel))  # a straight too short for the cruise speed
    s_ramp = 0.5 * peak * peak / accel
    t_ramp = peak / accel
    total = straight_s[seg]
    t = np.where(s <= s_ramp, np.sqrt(2.0 * s / accel),
                 np.where(s >= length - s_ramp, total - np.sqrt(2.0 * np.maximum(length - s, 0.0) / accel),
                          t_ramp + (s - s_ramp) / peak))
    out = clock[2 * seg] + t
    out[-1] = clock[-1]
    return out
