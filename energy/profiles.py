"""Stop-turn-go command profiles along a waypoint route (closed form, vectorised).

:func:`waypoint_commands` builds the profile along a polyline: at every waypoint where the
heading changes the robot stops, pivots in place to the next segment's heading (trapezoidal
yaw rate), then drives the next segment from rest (trapezoidal speed); it drives straight
through a waypoint where the heading does not change (:data:`COLLINEAR_TOL_RAD`).
:func:`drive_profile` is the same on a planned route (consecutive repeated waypoints
dropped): the motion a mission drives and a planner's costs price. :func:`drivable_waypoints`
and :func:`planned_durations_s` expose the route cleaning and the per-segment durations, in
closed form, without sampling.

**Collinear waypoints.** A robot stops only where it turns. Planned routes carry waypoints
where the heading does not change: the lattice's routes hold a vertex at every lattice node
(runs of one direction are collinear vertices), and joined routes (coarse-to-fine pieces, a
tour's legs) keep their junctions. A waypoint whose heading change is at most
:data:`COLLINEAR_TOL_RAD` is therefore driven through, not stopped at; the planner's edge
costs use the same constant (:meth:`planner.EnergyCost.turn_energy_at`: no turn, no stop and
go there), so the edges and the profile price the same drive.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from terrawatt_base.checks import check_optional_real, check_real
from terrawatt_base.errors import InvalidParameterError

from .commands import CommandProfile

__all__ = [
    "DEFAULT_ACCEL_MPS2",
    "DEFAULT_YAW_ACCEL_RADPS2",
    "COLLINEAR_TOL_RAD",
    "heading_changes_rad",
    "waypoint_commands",
    "pivot_commands",
    "drive_profile",
    "drivable_waypoints",
    "move_duration_s",
    "planned_durations_s",
    "terrain_along",
]

#: Default acceleration limits of the stop-turn-go profile (m/s^2, rad/s^2).
DEFAULT_ACCEL_MPS2 = 0.5
DEFAULT_YAW_ACCEL_RADPS2 = 1.0
#: Heading change (rad) at or below which a waypoint is driven through rather than stopped and pivoted at. Small
#: enough that only waypoints collinear to rounding qualify (a straight run's interior vertices: heading changes
#: of 0 or ~1e-16 rad); any real change of heading, however small, is a pivot in a stop-turn-go drive. The profile
#: (:func:`waypoint_commands`, :func:`drivable_waypoints`) and the edge costs (:mod:`planner.edge_cost`, its
#: compiled kernels) use this one value.
COLLINEAR_TOL_RAD = 1e-6


def heading_changes_rad(points_m: np.ndarray) -> np.ndarray:
    """Unsigned heading change (rad, in [0, pi]) at each interior vertex of a polyline without repeated points.

    Examples
    --------
    >>> heading_changes_rad(np.array([[0.0, 0], [1, 0], [2, 0], [2, 1]])).round(4).tolist()
    [0.0, 1.5708]
    """
    d = np.diff(points_m, axis=0)
    heading = np.arctan2(d[:, 1], d[:, 0])
    return np.abs(np.angle(np.exp(1j * np.diff(heading))))


def _pivots(points_m: np.ndarray, stops: np.ndarray | None = None) -> np.ndarray:
    """Indices of the vertices the profile stops at: both ends, every interior vertex that turns and the ``stops``."""
    turns = heading_changes_rad(points_m) > COLLINEAR_TOL_RAD
    if stops is not None and stops.size:
        turns[stops[(stops > 0) & (stops < points_m.shape[0] - 1)] - 1] = True
    return np.concatenate(([0], np.flatnonzero(turns) + 1, [points_m.shape[0] - 1]))


def _stops(stops: Any, n_points: int, name: str) -> np.ndarray:
    """The checked indices of the vertices a drive must stop at (ints in [0, n_points))."""
    if stops is None:
        return np.zeros(0, dtype=np.int64)
    try:
        out = np.asarray(stops, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be waypoint indices, got {stops!r:.80}") from None
    if out.size and (not np.all(np.isfinite(out)) or np.any(out != np.round(out)) or out.min() < 0
                     or out.max() >= n_points):
        raise InvalidParameterError(f"{name} must be indices of the {n_points} waypoints, got {stops!r:.80}")
    return out.astype(np.int64)


def _positive(name: str, value: Any) -> float:
    return check_real(name, value, low=0.0, low_inclusive=False)


def _trapezoid_times(distance: np.ndarray, v_max: float, a_max: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Peak speed, acceleration time and total time of rest-to-rest trapezoid moves."""
    full = distance >= v_max**2 / a_max
    peak = np.where(full, v_max, np.sqrt(distance * a_max))
    t_acc = peak / a_max
    with np.errstate(invalid="ignore", divide="ignore"):
        t_cruise = np.where(full, (distance - v_max**2 / a_max) / v_max, 0.0)
    return peak, t_acc, 2.0 * t_acc + t_cruise


def _trapezoid_eval(tau: np.ndarray, distance: np.ndarray, peak: np.ndarray, t_acc: np.ndarray,
                    total: np.ndarray, a_max: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and speed of a trapezoid move ``tau`` seconds after its start (clamped)."""
    tau = np.clip(tau, 0.0, total)
    t_dec = total - t_acc
    acc_phase = tau < t_acc
    dec_phase = tau > t_dec
    s_cruise = 0.5 * a_max * t_acc**2 + peak * (tau - t_acc)
    rem = total - tau
    s = np.where(acc_phase, 0.5 * a_max * tau**2, np.where(dec_phase, distance - 0.5 * a_max * rem**2, s_cruise))
    v = np.where(acc_phase, a_max * tau, np.where(dec_phase, a_max * rem, peak))
    return s, v


def waypoint_commands(
    waypoints_xy_m: Any,
    speed_mps: float,
    *,
    accel_mps2: float = DEFAULT_ACCEL_MPS2,
    turn_rate_radps: float = 0.5,
    yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2,
    dt_s: float = 0.01,
    start_heading_rad: float | None = None,
    stops: Any = None,
) -> CommandProfile:
    """Stop-turn-go commands along a polyline, with the reference pose.

    At each waypoint the robot turns in place to the next segment's heading (the shorter
    way round) with a trapezoidal yaw-rate profile (``turn_rate_radps``,
    ``yaw_accel_radps2``), then drives the segment from rest to rest with a trapezoidal
    speed profile (``speed_mps``, ``accel_mps2``); segments too short to reach the
    cruise speed get a triangular profile. A waypoint where the heading changes by at most
    :data:`COLLINEAR_TOL_RAD` is driven through: the segments on either side are one
    straight from rest to rest (the module docstring says why), unless it is one of ``stops``
    (the robot stops there whatever its heading: e.g. a tour's site). The first turn happens only
    when ``start_heading_rad`` is given. Positions and headings follow in closed form.

    Parameters
    ----------
    waypoints_xy_m : array_like, shape (K, 2)
        Route vertices (m), K >= 2, no two consecutive ones equal.
    speed_mps : float
        Cruise speed (m/s), > 0.
    accel_mps2, turn_rate_radps, yaw_accel_radps2 : float
        Acceleration limit (m/s^2), pivot yaw rate (rad/s) and yaw-acceleration limit
        (rad/s^2), all > 0.
    dt_s : float
        Sampling period (s), > 0.
    start_heading_rad : float, optional
        Heading at the start; ``None`` starts facing the first segment.
    stops : sequence of int, optional
        Indices of waypoints the robot stops at even where it drives on in the heading it came.

    Returns
    -------
    CommandProfile
        Samples ``k * dt_s`` up to the first one at or after the end of the route (which
        is at rest at the last waypoint), with ``pose_xyh`` (heading wrapped to (-pi, pi]).

    Raises
    ------
    InvalidParameterError
        Bad shapes, non-finite or repeated waypoints, non-positive limits.

    Examples
    --------
    >>> p = waypoint_commands([[0.0, 0.0], [2.0, 0.0]], 0.5, dt_s=0.05)
    >>> round(float(p.pose_xyh[-1, 0]), 6), float(p.v_mps[-1])
    (2.0, 0.0)
    """
    try:
        wp = np.array(waypoints_xy_m, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"waypoints_xy_m must be a numeric (K, 2) array, got {waypoints_xy_m!r:.80}") from None
    if wp.ndim != 2 or wp.shape[1] != 2 or wp.shape[0] < 2:
        raise InvalidParameterError(f"waypoints_xy_m must have shape (K, 2) with K >= 2, got {wp.shape!r}")
    if not np.all(np.isfinite(wp)):
        raise InvalidParameterError("waypoints_xy_m must be finite (no NaN or inf)")
    v_max = _positive("speed_mps", speed_mps)
    a_max = _positive("accel_mps2", accel_mps2)
    w_max = _positive("turn_rate_radps", turn_rate_radps)
    al_max = _positive("yaw_accel_radps2", yaw_accel_radps2)
    dt = _positive("dt_s", dt_s)
    delta = np.diff(wp, axis=0)
    length = np.hypot(delta[:, 0], delta[:, 1])
    if np.any(length == 0):
        i = int(np.argmax(length == 0))
        raise InvalidParameterError(
            f"waypoints_xy_m[{i}] and waypoints_xy_m[{i + 1}] are equal ({wp[i].tolist()!r}); "
            "remove repeated waypoints"
        )
    keep = _stops(stops, wp.shape[0], "stops")
    if wp.shape[0] > 2:  # drive through collinear waypoints
        wp = wp[_pivots(wp, keep)]
        delta = np.diff(wp, axis=0)
        length = np.hypot(delta[:, 0], delta[:, 1])
    heading = np.arctan2(delta[:, 1], delta[:, 0])
    h_start = check_optional_real("start_heading_rad", start_heading_rad)
    if h_start is None:
        h_start = heading[0]
    prev = np.concatenate(([h_start], heading[:-1]))
    turn = np.angle(np.exp(1j * (heading - prev)))  # wrapped to (-pi, pi]
    k = heading.size
    # phases alternate: turn_0, straight_0, turn_1, straight_1, ...
    dist = np.empty(2 * k)
    dist[0::2] = np.abs(turn)
    dist[1::2] = length
    is_turn = np.zeros(2 * k, dtype=bool)
    is_turn[0::2] = True
    peak = np.empty(2 * k)
    t_acc = np.empty(2 * k)
    total = np.empty(2 * k)
    for mask, vm, am in ((is_turn, w_max, al_max), (~is_turn, v_max, a_max)):
        p, ta, tt = _trapezoid_times(dist[mask], vm, am)
        peak[mask], t_acc[mask], total[mask] = p, ta, tt
    starts = np.concatenate(([0.0], np.cumsum(total)))
    t_end = float(starts[-1])
    n = int(math.ceil(t_end / dt - 1e-9)) + 1
    t = np.arange(n, dtype=np.float64) * dt
    phase = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, 2 * k - 1)
    tau = t - starts[phase]
    a_phase = np.where(is_turn[phase], al_max, a_max)
    s, rate = _trapezoid_eval(tau, dist[phase], peak[phase], t_acc[phase], total[phase], a_phase)
    seg = phase // 2
    turning = is_turn[phase]
    sign = np.sign(turn[seg])
    v = np.where(turning, 0.0, rate)
    omega = np.where(turning, sign * rate, 0.0)
    unit = delta / length[:, None]
    xy = np.where(turning[:, None], wp[seg], wp[seg] + s[:, None] * unit[seg])
    h = np.where(turning, prev[seg] + sign * s, heading[seg])
    h = np.pi - np.mod(np.pi - h, 2.0 * np.pi)
    return CommandProfile(t, v, omega, np.column_stack([xy, h]))


def pivot_commands(angle_rad: float, *, turn_rate_radps: float, yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2,
                   dt_s: float = 0.01) -> CommandProfile:
    """The pivot of :func:`waypoint_commands` alone: a turn in place by ``|angle_rad|`` from rest to rest.

    The same trapezoidal (or triangular) yaw-rate profile a stop-turn-go drive pivots with at a
    waypoint, counter-clockwise from heading 0 at the origin; what the planner's turn tables
    price (:func:`planner.tables.stop_turn_go_rows`).

    Parameters
    ----------
    angle_rad : float
        Heading change (rad; the sign is ignored), at most pi.
    turn_rate_radps, yaw_accel_radps2 : float
        Pivot yaw rate (rad/s) and yaw-acceleration limit (rad/s^2), > 0.
    dt_s : float
        Sampling period (s), > 0.

    Returns
    -------
    CommandProfile
        Samples ``k * dt_s`` up to the first at or after the pivot's end (at rest), with poses.

    Raises
    ------
    InvalidParameterError
        An angle outside [-pi, pi], non-positive limits.

    Examples
    --------
    >>> p = pivot_commands(1.0, turn_rate_radps=0.5, yaw_accel_radps2=1.0, dt_s=0.01)
    >>> round(p.duration_s, 6), round(float(p.pose_xyh[-1, 2]), 6)
    (2.5, 1.0)
    """
    angle = abs(check_real("angle_rad", angle_rad, low=-math.pi, high=math.pi))
    w_max = _positive("turn_rate_radps", turn_rate_radps)
    al_max = _positive("yaw_accel_radps2", yaw_accel_radps2)
    dt = _positive("dt_s", dt_s)
    dist = np.array([angle])
    peak, t_acc, total = _trapezoid_times(dist, w_max, al_max)
    n = int(math.ceil(float(total[0]) / dt - 1e-9)) + 1
    t = np.arange(n, dtype=np.float64) * dt
    s, rate = _trapezoid_eval(t, dist, peak, t_acc, total, al_max)
    zeros = np.zeros(n)
    return CommandProfile(t, zeros, rate, np.column_stack([zeros, zeros, s]))


def drivable_waypoints(waypoints_m: Any, *, stops: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """A route's waypoints without consecutive repeats or collinear vertices, and the route segment each kept one starts at.

    The vertices the stop-turn-go profile stops at (:func:`waypoint_commands`): repeated
    waypoints are dropped, and so is every interior vertex whose heading change is at most
    :data:`COLLINEAR_TOL_RAD` (driven through) that is not one of ``stops``; a kept segment then
    spans several route segments, from the one in ``kept`` to the next kept one.

    Parameters
    ----------
    waypoints_m : array_like, shape (K, 2)
        Route vertices (m).
    stops : sequence of int, optional
        Indices of waypoints the robot stops at whatever its heading there (kept even where
        collinear; a repeated waypoint stands for its last copy).

    Returns
    -------
    points : ndarray, shape (M + 1, 2)
        The vertices of the ``M`` driven segments (each of positive length).
    kept : ndarray of int, shape (M,), increasing
        Index in the original route of the first route segment of each driven segment.

    Raises
    ------
    InvalidParameterError
        Not a finite (K >= 2, 2) array, or no segment of positive length.

    Examples
    --------
    >>> pts, kept = drivable_waypoints([[0, 0], [0, 0], [1, 0]])
    >>> pts.tolist(), kept.tolist()
    ([[0.0, 0.0], [1.0, 0.0]], [1])
    >>> pts, kept = drivable_waypoints([[0, 0], [1, 0], [2, 0], [2, 1]])  # driven through (1, 0)
    >>> pts.tolist(), kept.tolist()
    ([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0]], [0, 2])
    >>> drivable_waypoints([[0, 0], [1, 0], [2, 0], [2, 1]], stops=[1])[1].tolist()  # stopped at (1, 0)
    [0, 1, 2]
    """
    try:
        wp = np.asarray(waypoints_m, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"waypoints_m must be a numeric (K, 2) array, got {waypoints_m!r:.80}") from None
    if wp.ndim != 2 or wp.shape[1] != 2 or len(wp) < 2:
        raise InvalidParameterError(f"waypoints_m must have shape (K >= 2, 2), got {wp.shape!r}")
    if not np.all(np.isfinite(wp)):
        raise InvalidParameterError("waypoints_m must be finite (no NaN or inf)")
    at = _stops(stops, wp.shape[0], "stops")
    length = np.hypot(*np.diff(wp, axis=0).T)
    keep_seg = np.flatnonzero(length > 0)
    if keep_seg.size == 0:
        raise InvalidParameterError(f"route has no segment of positive length (waypoints {wp.tolist()!r})")
    pts = np.vstack([wp[keep_seg], wp[keep_seg[-1] + 1][None, :]])
    if pts.shape[0] > 2:
        # a stop at waypoint s is the vertex that starts the first kept segment from s on
        pivots = _pivots(pts, np.searchsorted(keep_seg, at) if at.size else None)
        pts, keep_seg = pts[pivots], keep_seg[pivots[:-1]]
    return pts, keep_seg


def drive_profile(
    waypoints_m: Any,
    speed_mps: float,
    *,
    turn_rate_radps: float,
    dt_s: float,
    accel_mps2: float = DEFAULT_ACCEL_MPS2,
    yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2,
    start_heading_rad: float | None = None,
    stops: Any = None,
) -> CommandProfile:
    """The stop-turn-go command profile a mission drives along ``waypoints_m``.

    Consecutive repeated waypoints are dropped and collinear ones other than ``stops`` driven
    through (:func:`drivable_waypoints`); then :func:`waypoint_commands` (pivot to each segment's
    heading, drive it rest to rest at ``speed_mps``).

    Raises
    ------
    InvalidParameterError
        Fewer than two distinct waypoints, or bad speeds, rates or ``dt_s``.

    Examples
    --------
    >>> p = drive_profile([[0, 0], [0, 0], [2, 0]], 0.5, turn_rate_radps=0.5, dt_s=0.05)
    >>> round(p.duration_s, 6)
    5.0
    """
    pts, kept = drivable_waypoints(waypoints_m, stops=stops)
    return waypoint_commands(pts, speed_mps, accel_mps2=accel_mps2, turn_rate_radps=turn_rate_radps,
                             yaw_accel_radps2=yaw_accel_radps2, dt_s=dt_s, start_heading_rad=start_heading_rad,
                             stops=np.arange(1, len(kept)) if stops is not None else None)


def move_duration_s(distance: Any, peak: float, accel: float) -> np.ndarray:
    """Duration of rest-to-rest trapezoidal (or triangular) moves (s).

    ``distance`` in m (or rad), ``peak`` the cruise speed (m/s or rad/s) and ``accel`` the
    acceleration limit (m/s^2 or rad/s^2), both > 0 (not checked: a hot-path helper).

    Examples
    --------
    >>> move_duration_s([2.0, 0.125], 0.5, 0.5).tolist()
    [5.0, 1.0]
    """
    distance = np.asarray(distance, dtype=np.float64)
    full = distance >= peak * peak / accel
    return np.where(full, distance / peak + peak / accel, 2.0 * np.sqrt(distance / accel))


def planned_durations_s(points_m: np.ndarray, start_heading_rad: float | None, speed_mps: float, accel_mps2: float,
                        turn_rate_radps: float, yaw_accel_radps2: float) -> tuple[np.ndarray, np.ndarray]:
    """Durations (s) of the turn and of the straight of each segment of the stop-turn-go profile.

    ``points_m`` are drivable waypoints (:func:`drivable_waypoints`); the turn at waypoint
    ``k`` starts segment ``k`` (none at the start unless ``start_heading_rad`` is given).

    Examples
    --------
    >>> turn, straight = planned_durations_s(np.array([[0.0, 0], [2, 0]]), None, 0.5, 0.5, 0.5, 1.0)
    >>> turn.tolist(), straight.tolist()
    ([0.0], [5.0])
    """
    d = np.diff(points_m, axis=0)
    heading = np.arctan2(d[:, 1], d[:, 0])
    start = 0.0 if start_heading_rad is None else abs(float(np.angle(np.exp(1j * (heading[0] - start_heading_rad)))))
    turn = np.concatenate(([start], heading_changes_rad(points_m)))
    return (move_duration_s(turn, turn_rate_radps, yaw_accel_radps2),
            move_duration_s(np.hypot(d[:, 0], d[:, 1]), speed_mps, accel_mps2))


def terrain_along(terrain: Any, x_m: Any, y_m: Any, heading_rad: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What a pose meets on a map: its cell, the pitch along its heading and the tilt of the vertical.

    The pitch is ``arctan(grad_x cos h + grad_y sin h)`` (positive uphill) and the cosine of
    the tilt ``1 / sqrt(1 + |grad|**2)``, from the bilinearly interpolated gradients; the
    truth simulator and the physics forecast of a driven profile use this one rule.

    Parameters
    ----------
    terrain : TerrainMap
    x_m, y_m, heading_rad : array_like, shape (N,)
        Poses (m, m, rad).

    Returns
    -------
    rows, cols : numpy.ndarray of int
    slope_rad, cos_tilt : numpy.ndarray of float

    Raises
    ------
    OutOfBoundsError
        A pose off the map.
    """
    x = np.asarray(x_m, dtype=np.float64)
    y = np.asarray(y_m, dtype=np.float64)
    h = np.asarray(heading_rad, dtype=np.float64)
    rows, cols = terrain.rowcol(x, y)
    gx = np.asarray(terrain.sample("grad_x", x, y, method="bilinear"), dtype=np.float64)
    gy = np.asarray(terrain.sample("grad_y", x, y, method="bilinear"), dtype=np.float64)
    return rows, cols, np.arctan(gx * np.cos(h) + gy * np.sin(h)), 1.0 / np.sqrt(1.0 + gx * gx + gy * gy)
