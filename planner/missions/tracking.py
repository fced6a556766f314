"""Where a driven log is along its route: samples to segments by pose, the planning speed of a route."""

from __future__ import annotations

import math

import numpy as np

from terrawatt_base.checks import fmt_number
from terrawatt_base.errors import InvalidParameterError

from ..route import Route
from ..route_time import route_duration_s

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


def route_speed_mps(route: Route, turn_rate: float) -> float:
    """Planning speed recovered from a route's duration: the cruise speed at which the stop-turn-go drive of its
    waypoints lasts ``route.duration_s`` (:func:`planner.route_time.route_duration_s`, the rule that set it; the
    duration falls as the speed rises, so a bisection finds it to rounding)."""
    wp = route.waypoints_m
    target = float(route.duration_s)
    lo, hi = 1e-6, 1e3

    def duration(v: float) -> float:
        return route_duration_s(wp, v, turn_rate)

    if not (math.isfinite(target) and duration(hi) <= target <= duration(lo)):
        raise InvalidParameterError(
            f"cannot recover the planning speed from route.duration_s={fmt_number(route.duration_s)} s (no cruise "
            f"speed gives the stop-turn-go drive that duration at turn_rate_radps={fmt_number(turn_rate)}); "
            "pass speed_mps or cost"
        )
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        if mid in (lo, hi):
            break
        lo, hi = (mid, hi) if duration(mid) > target else (lo, mid)
    return hi if abs(duration(hi) - target) <= abs(duration(lo) - target) else lo

