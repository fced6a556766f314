"""Where a driven log is along its route: samples to segments by pose, the planning speed of a route."""

from __future__ import annotations

import math

import numpy as np

from terrain import TerrainMap
from terrawatt_base.checks import fmt_number
from terrawatt_base.errors import InvalidParameterError

from ..route import Route

__all__ = ["segments_by_pose", "route_speed_mps"]


def segments_by_pose(xy: np.ndarray, pts: np.ndarray, tol_m: float) -> tuple[np.ndarray, int]:
    """Segment of each pose, walking the polyline in time order.

    Segment ``k`` ends at the first sample from which the robot's progress along it is
    within ``tol_m`` of its end, advanced to the robot's closest approach to the end
    waypoint. Returns the segment indices and the number of segment ends reached.
    """
    n = xy.shape[0]
    n_seg = pts.shape[0] - 1
    idx = np.zeros(n, dtype=np.int64)
    start = 0
    reached = 0
    for k in range(n_seg):
        a, b = pts[k], pts[k + 1]
        length = float(np.hypot(*(b - a)))
        rest = xy[start:]
        along = (rest - a) @ ((b - a) / length)
        hit = np.flatnonzero(along >= length - tol_m)
        if hit.size == 0:
            break
        i = start + int(hit[0])
        dist = np.hypot(xy[i:, 0] - b[0], xy[i:, 1] - b[1])
        rising = np.flatnonzero(np.diff(dist) >= 0)
        j = i + (int(rising[0]) if rising.size else dist.size - 1)
        if dist[j - i] > tol_m:
            break
        reached = k + 1
        if k + 1 < n_seg:
            idx[j:] = k + 1
            start = j
    return idx, reached


def route_speed_mps(terrain: TerrainMap, route: Route, turn_rate: float) -> float:
    """Planning speed recovered from a route's duration: surface length / (duration - turning time)."""
    wp = route.waypoints_m
    gx, gy = terrain["grad_x"], terrain["grad_y"]
    surface = 0.0
    for a, b in zip(wp[:-1], wp[1:]):
        length = math.hypot(b[0] - a[0], b[1] - a[1])
        if length == 0.0:
            continue
        rows, cols, pieces = terrain.segment_cells(tuple(a), tuple(b))
        grade = (gx[rows, cols] * (b[0] - a[0]) + gy[rows, cols] * (b[1] - a[1])) / length
        surface += float(np.sum(pieces * np.sqrt(1.0 + grade**2)))
    d = np.diff(wp, axis=0)
    nz = np.flatnonzero(np.hypot(d[:, 0], d[:, 1]) > 0)
    heading = np.arctan2(d[nz, 1], d[nz, 0])
    turning_s = float(np.sum(np.abs(np.angle(np.exp(1j * np.diff(heading)))))) / turn_rate
    drive_s = route.duration_s - turning_s
    speed = surface / drive_s if drive_s > 0 else math.nan
    if not (math.isfinite(speed) and speed > 0):
        raise InvalidParameterError(
            f"cannot recover the planning speed from route.duration_s={fmt_number(route.duration_s)} s (turning "
            f"time {fmt_number(turning_s)} s at turn_rate_radps={fmt_number(turn_rate)}); pass speed_mps or cost"
        )
    return speed

