"""Mission simulation: drive a route against a truth simulator or a recorded log, with an energy budget.

:func:`simulate_mission` turns a :class:`~planner.route.Route` into a drivable velocity
profile, drives it (or replays a log that drove it) and returns a :class:`MissionResult`:
the time series (pose, speeds, side currents, battery power, cumulative Wh and mAh, state of
charge, route segment) and an :class:`~energy.battery.EnergyBudget` comparing the predicted
energy with the actual one, with the reserve at arrival, the feasibility against the
battery and a per-segment breakdown.

Velocity profile (stop-turn-go, :func:`energy.waypoint_commands`): at every waypoint the
robot stops and pivots in place to the next segment's heading at the turn rate (trapezoidal
yaw rate, ``yaw_accel_radps2``), then drives the segment from rest to rest at the planning
speed (trapezoidal speed, ``accel_mps2``). This is the motion the planner's costs price:
straight segments at the planning speed plus turns in place at the waypoints. Turning
smoothly (arcs) is not modelled.

Segments: the turn at waypoint ``k`` belongs to segment ``k`` (the one it starts), as in
``Route.turn_energy_j``; so the predicted energy of segment ``k`` is
``segment_energy_j[k] + turn_energy_j[k]`` and the segments add up to ``Route.energy_j``.
Driven samples are assigned to segments from the log's pose (each segment ends at the
robot's closest approach to its end waypoint once it is within ``waypoint_tolerance_m``
along the segment); a log without a pose is assumed to follow the velocity profile from its
first sample and is assigned by time.

Actual power: :func:`energy.log_battery_power_w` on the driven log (drive power from the
logged side currents plus the robot's electronics), so driving with a
:class:`~energy.truth.TruthSimulator` and replaying the log it produced give the same
result, and the actual energy is booked like the physics model that priced the route.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from energy import (
    CURRENT_CONVENTIONS,
    Battery,
    CommandProfile,
    EnergyBudget,
    InteractionLog,
    RobotParams,
    TruthSimulator,
    discharge_from_power,
    energy_budget,
    log_battery_power_w,
    waypoint_commands,
)
from terrain import TerrainMap
from terrain.atomic import atomic_path, write_text_atomic
from terrain.errors import (
    DataError,
    GridMismatchError,
    InvalidParameterError,
    OutOfBoundsError,
    UnknownNameError,
)

from .edge_cost import EnergyCost
from .route import Route

#: Default acceleration limits of the stop-turn-go profile (m/s^2, rad/s^2).
DEFAULT_ACCEL_MPS2 = 0.5
DEFAULT_YAW_ACCEL_RADPS2 = 1.0

__all__ = [
    "MissionResult",
    "MISSION_STATUSES",
    "MISSION_FORMAT_VERSION",
    "simulate_mission",
    "drive_profile",
    "DEFAULT_ACCEL_MPS2",
    "DEFAULT_YAW_ACCEL_RADPS2",
]

#: ``completed``: the route was driven to its end with the state of charge at or above the
#: reserve throughout. ``reserve_violated``: the state of charge went below the reserve
#: (the crossing point is reported; with ``stop_at_reserve`` the series ends there).
MISSION_STATUSES = ("completed", "reserve_violated")
#: Version of the JSON written by :meth:`MissionResult.save_json`.
MISSION_FORMAT_VERSION = 1
_FORMAT_NAME = "terrawatt-mission"

_SERIES = (
    "time_s",
    "x_m",
    "y_m",
    "heading_rad",
    "v_mps",
    "omega_radps",
    "current_left_a",
    "current_right_a",
    "power_w",
    "battery_current_a",
    "energy_wh",
    "predicted_energy_wh",
    "charge_mah",
    "soc",
)


def _real(name: str, value: Any, *, low: float | None = None, low_open: bool = True) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidParameterError(f"{name} must be a finite number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise InvalidParameterError(f"{name} must be a finite number, got {value!r}")
    if low is not None and (v < low or (low_open and v == low)):
        raise InvalidParameterError(f"{name} must be {'>' if low_open else '>='} {low!r}, got {value!r}")
    return v


def _readonly(a: Any, dtype: Any = np.float64) -> np.ndarray:
    arr = np.array(a, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False, repr=False)
class MissionResult:
    """A driven (or replayed) route: time series and energy budget.

    Attributes
    ----------
    status : str
        One of :data:`MISSION_STATUSES`.
    source : str
        ``"truth"`` (driven with a TruthSimulator) or ``"replay"`` (a recorded log).
    route : Route
        The route that was driven.
    budget : EnergyBudget
        Predicted vs actual energy, reserve at arrival, feasibility, per-segment breakdown
        (one entry per route segment).
    time_s : ndarray, shape (N,)
        Sample times from the start of the mission (s).
    x_m, y_m, heading_rad : ndarray, shape (N,)
        Pose (m, m, rad).
    v_mps, omega_radps : ndarray, shape (N,)
        Speed and yaw rate of the log (commanded or measured, see ``log.meta``).
    current_left_a, current_right_a : ndarray, shape (N,)
        Logged side currents (A; their meaning is ``current_convention``).
    power_w : ndarray, shape (N,)
        Battery-side power: drive plus electronics (W).
    battery_current_a : ndarray, shape (N,)
        Battery current delivering ``power_w`` (A).
    energy_wh, predicted_energy_wh : ndarray, shape (N,)
        Cumulative actual energy and the prediction spread over each segment's samples in
        proportion to time (Wh).
    charge_mah : ndarray, shape (N,)
        Cumulative battery charge (mAh).
    soc : ndarray, shape (N,)
        State of charge (fraction).
    segment_index : ndarray of int, shape (N,)
        Route segment of each sample.
    reserve_crossed_time_s : float or None
        When the state of charge reached the reserve, or None.
    reserve_crossed_xy_m : (float, float) or None
        Where (interpolated along the driven path).
    reserve_crossed_segment : int or None
        In which route segment.
    speed_mps, accel_mps2, turn_rate_radps, yaw_accel_radps2 : float
        The velocity profile.
    current_convention : str
        How the side currents were turned into power (see
        :func:`energy.log_battery_power_w`).
    truth_energy_j : float
        Noise-free battery energy of the truth simulator over the same samples (J; NaN
        for a replay). ``budget.actual_energy_j`` is what the logged (measured) currents
        give; the two differ by the measurement model.
    log : InteractionLog
        The driven log (with pose), for per-cell comparisons.

    Derived: ``n_samples``, ``duration_s``, ``feasible``, ``completed``. Methods:
    :meth:`to_json_dict`, :meth:`save_json`, :meth:`plot`.
    """

    status: str
    source: str
    route: Route
    budget: EnergyBudget
    time_s: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    heading_rad: np.ndarray
    v_mps: np.ndarray
    omega_radps: np.ndarray
    current_left_a: np.ndarray
    current_right_a: np.ndarray
    power_w: np.ndarray
    battery_current_a: np.ndarray
    energy_wh: np.ndarray
    predicted_energy_wh: np.ndarray
    charge_mah: np.ndarray
    soc: np.ndarray
    segment_index: np.ndarray
    reserve_crossed_time_s: float | None
    reserve_crossed_xy_m: tuple[float, float] | None
    reserve_crossed_segment: int | None
    speed_mps: float
    accel_mps2: float
    turn_rate_radps: float
    yaw_accel_radps2: float
    current_convention: str
    truth_energy_j: float
    log: InteractionLog

    def __post_init__(self) -> None:
        if self.status not in MISSION_STATUSES:
            raise InvalidParameterError(f"status must be one of {MISSION_STATUSES!r}, got {self.status!r}")
        if self.source not in ("truth", "replay"):
            raise InvalidParameterError(f"source must be 'truth' or 'replay', got {self.source!r}")
        if not isinstance(self.route, Route):
            raise InvalidParameterError(f"route must be a Route, got {type(self.route).__name__!r}")
        if not isinstance(self.budget, EnergyBudget):
            raise InvalidParameterError(f"budget must be an EnergyBudget, got {type(self.budget).__name__!r}")
        if not isinstance(self.log, InteractionLog):
            raise InvalidParameterError(f"log must be an InteractionLog, got {type(self.log).__name__!r}")
        n = np.shape(self.time_s)
        if len(n) != 1 or n[0] < 2:
            raise InvalidParameterError(f"time_s must be 1-D with at least 2 samples, got shape {n!r}")
        for name in _SERIES:
            arr = _readonly(getattr(self, name))
            if arr.shape != n:
                raise InvalidParameterError(f"{name} must have shape {n!r}, got {arr.shape!r}")
            object.__setattr__(self, name, arr)
        seg = _readonly(self.segment_index, np.int64)
        if seg.shape != n:
            raise InvalidParameterError(f"segment_index must have shape {n!r}, got {seg.shape!r}")
        object.__setattr__(self, "segment_index", seg)
        if (self.status == "reserve_violated") == self.budget.feasible:
            raise InvalidParameterError(
                f"status {self.status!r} contradicts budget.feasible={self.budget.feasible!r}"
            )
        if self.current_convention not in CURRENT_CONVENTIONS:
            raise UnknownNameError(
                f"current_convention must be one of {CURRENT_CONVENTIONS!r}, got {self.current_convention!r}"
            )

    # ------------------------------------------------------------------ derived
    @property
    def n_samples(self) -> int:
        """Number of samples of the series."""
        return int(self.time_s.size)

    @property
    def duration_s(self) -> float:
        """Duration of the series (s)."""
        return float(self.time_s[-1] - self.time_s[0])

    @property
    def feasible(self) -> bool:
        """The state of charge stayed at or above the reserve."""
        return self.budget.feasible

    @property
    def completed(self) -> bool:
        """``status == "completed"``."""
        return self.status == "completed"

    # ---------------------------------------------------------------- output
    def to_json_dict(self, *, series_every: int = 1) -> dict[str, Any]:
        """JSON-ready values: format fields, settings, route, budget, crossing, series.

        Parameters
        ----------
        series_every : int
            Keep every ``series_every``-th sample of the time series (>= 1; the last
            sample is always kept). The budget is computed from all samples.

        Raises
        ------
        InvalidParameterError
            ``series_every`` not an int >= 1.
        """
        if isinstance(series_every, bool) or not isinstance(series_every, (int, np.integer)) or series_every < 1:
            raise InvalidParameterError(f"series_every must be an int >= 1, got {series_every!r}")
        keep = np.arange(0, self.n_samples, int(series_every))
        if keep[-1] != self.n_samples - 1:
            keep = np.append(keep, self.n_samples - 1)
        series: dict[str, list[Any]] = {name: getattr(self, name)[keep].tolist() for name in _SERIES}
        series["segment_index"] = self.segment_index[keep].tolist()
        route = self.route.summary()
        route = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in route.items()}
        route["waypoints_m"] = self.route.waypoints_m.tolist()
        route["segment_energy_j"] = self.route.segment_energy_j.tolist()
        route["turn_energy_j"] = self.route.turn_energy_j.tolist()
        return {
            "format": _FORMAT_NAME,
            "format_version": MISSION_FORMAT_VERSION,
            "status": self.status,
            "source": self.source,
            "settings": {
                "speed_mps": self.speed_mps,
                "accel_mps2": self.accel_mps2,
                "turn_rate_radps": self.turn_rate_radps,
                "yaw_accel_radps2": self.yaw_accel_radps2,
                "current_convention": self.current_convention,
                "robot": self.log.meta.robot,
                "log_source": self.log.meta.source,
            },
            "route": route,
            "budget": self.budget.to_json_dict(),
            "reserve_crossing": None
            if self.reserve_crossed_time_s is None
            else {
                "time_s": self.reserve_crossed_time_s,
                "xy_m": list(self.reserve_crossed_xy_m),
                "segment": self.reserve_crossed_segment,
            },
            "truth_energy_j": None if not math.isfinite(self.truth_energy_j) else self.truth_energy_j,
            "duration_s": self.duration_s,
            "series_every": int(series_every),
            "series": series,
        }

    def save_json(self, path: str | os.PathLike[str], *, series_every: int = 1) -> Path:
        """Write :meth:`to_json_dict` to a file atomically (temporary file, then rename).

        Returns
        -------
        Path
            The written file.

        Raises
        ------
        InvalidParameterError
            ``series_every`` not an int >= 1.
        """
        payload = json.dumps(self.to_json_dict(series_every=series_every), allow_nan=False)
        return write_text_atomic(path, payload)

    def plot(self, path: str | os.PathLike[str], terrain: TerrainMap | None = None, *,
             title: str | None = None, dpi: int = 110) -> Path:
        """Write a PNG: SoC over time, predicted vs actual cumulative energy, and the driven
        path coloured by battery power (over the map's elevation when ``terrain`` is given).

        Written atomically with matplotlib's Agg backend (no display needed).

        Returns
        -------
        Path
            The written file.
        """
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.collections import LineCollection
        from matplotlib.figure import Figure

        fig = Figure(figsize=(13.5, 4.2))
        FigureCanvasAgg(fig)
        ax_soc, ax_e, ax_map = fig.subplots(1, 3, gridspec_kw={"width_ratios": [1, 1, 1.1]})
        t = self.time_s
        reserve = self.budget.battery.min_reserve_pct
        ax_soc.plot(t, 100.0 * self.soc, color="tab:blue", label="state of charge")
        ax_soc.axhline(reserve, color="tab:red", linestyle="--", label=f"reserve {reserve:g} %")
        if self.reserve_crossed_time_s is not None:
            ax_soc.axvline(self.reserve_crossed_time_s, color="tab:red", linewidth=0.8)
        ax_soc.set_xlabel("time (s)")
        ax_soc.set_ylabel("state of charge (%)")
        ax_soc.legend(loc="best", fontsize=8)

        ax_e.plot(t, self.energy_wh, color="tab:orange", label=f"actual {self.budget.actual_energy_wh:.2f} Wh")
        ax_e.plot(t, self.predicted_energy_wh, color="tab:gray", linestyle="--",
                  label=f"predicted {self.budget.predicted_energy_wh:.2f} Wh ({self.budget.error_pct:+.1f} %)")
        ax_e.set_xlabel("time (s)")
        ax_e.set_ylabel("cumulative energy (Wh)")
        ax_e.legend(loc="best", fontsize=8)

        if terrain is not None:
            xmin, ymin, xmax, ymax = terrain.bounds
            ax_map.imshow(terrain.elevation_m, origin="lower", extent=(xmin, xmax, ymin, ymax), cmap="Greys",
                          alpha=0.6)
            obst = np.ma.masked_where(~np.asarray(terrain.obstacle), np.ones(terrain.shape))
            ax_map.imshow(obst, origin="lower", extent=(xmin, xmax, ymin, ymax), cmap="binary", vmin=0, vmax=1)
        pts = np.column_stack([self.x_m, self.y_m])
        segs = np.stack([pts[:-1], pts[1:]], axis=1)
        lc = LineCollection(segs, cmap="plasma", linewidths=2.5)
        lc.set_array(0.5 * (self.power_w[:-1] + self.power_w[1:]))
        ax_map.add_collection(lc)
        fig.colorbar(lc, ax=ax_map, label="battery power (W)")
        wp = self.route.waypoints_m
        ax_map.plot(wp[:, 0], wp[:, 1], "o", color="black", markersize=3, label="waypoints")
        if self.reserve_crossed_xy_m is not None:
            ax_map.plot(*self.reserve_crossed_xy_m, "X", color="tab:red", markersize=10, label="reserve crossed")
        ax_map.set_aspect("equal")
        ax_map.autoscale_view()
        ax_map.set_xlabel("x (m)")
        ax_map.set_ylabel("y (m)")
        ax_map.legend(loc="best", fontsize=8)
        fig.suptitle(title or f"mission {self.status}: {self.budget.actual_energy_wh:.2f} Wh, "
                     f"arrival SoC {self.budget.arrival_soc_pct:.1f} %")
        fig.tight_layout()
        path = Path(path)
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format="png")
        return path

    def __repr__(self) -> str:
        b = self.budget
        return (
            f"MissionResult(status={self.status!r}, source={self.source!r}, samples={self.n_samples}, "
            f"duration_s={self.duration_s:.1f}, predicted_wh={b.predicted_energy_wh:.3f}, "
            f"actual_wh={b.actual_energy_wh:.3f}, error_pct={b.error_pct:+.2f}, "
            f"arrival_soc_pct={b.arrival_soc_pct:.2f}, reserve_crossed_time_s={self.reserve_crossed_time_s!r})"
        )


def _drivable_waypoints(wp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Waypoints without consecutive repeats, and the route segment of each kept segment."""
    length = np.hypot(*np.diff(wp, axis=0).T)
    keep_seg = np.flatnonzero(length > 0)
    if keep_seg.size == 0:
        raise InvalidParameterError(f"route has no segment of positive length (waypoints {wp.tolist()!r})")
    pts = np.vstack([wp[keep_seg], wp[keep_seg[-1] + 1][None, :]])
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
) -> CommandProfile:
    """The stop-turn-go command profile :func:`simulate_mission` drives along ``waypoints_m``.

    Consecutive repeated waypoints are dropped; then :func:`energy.waypoint_commands`
    (pivot to each segment's heading, drive it rest to rest at ``speed_mps``).

    Raises
    ------
    InvalidParameterError
        Fewer than two distinct waypoints, or bad speeds, rates or ``dt_s``.
    """
    wp = np.asarray(waypoints_m, dtype=np.float64)
    if wp.ndim != 2 or wp.shape[1] != 2 or len(wp) < 2:
        raise InvalidParameterError(f"waypoints_m must have shape (K >= 2, 2), got {wp.shape!r}")
    pts, _ = _drivable_waypoints(wp)
    return waypoint_commands(pts, speed_mps, accel_mps2=accel_mps2, turn_rate_radps=turn_rate_radps,
                             yaw_accel_radps2=yaw_accel_radps2, dt_s=dt_s, start_heading_rad=start_heading_rad)


def _move_duration_s(distance: np.ndarray, peak: float, accel: float) -> np.ndarray:
    """Duration of a rest-to-rest trapezoidal (or triangular) move."""
    full = distance >= peak * peak / accel
    return np.where(full, distance / peak + peak / accel, 2.0 * np.sqrt(distance / accel))


def _planned_durations_s(pts: np.ndarray, start_heading_rad: float | None, speed: float, accel: float,
                         turn_rate: float, yaw_accel: float) -> tuple[np.ndarray, np.ndarray]:
    """Durations of the turn and of the straight of each drivable segment of the stop-turn-go profile."""
    d = np.diff(pts, axis=0)
    heading = np.arctan2(d[:, 1], d[:, 0])
    prev = np.concatenate(([heading[0] if start_heading_rad is None else start_heading_rad], heading[:-1]))
    turn = np.abs(np.angle(np.exp(1j * (heading - prev))))
    return _move_duration_s(turn, turn_rate, yaw_accel), _move_duration_s(np.hypot(d[:, 0], d[:, 1]), speed, accel)


def _segments_by_pose(xy: np.ndarray, pts: np.ndarray, tol_m: float) -> tuple[np.ndarray, int]:
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


def _route_speed_mps(terrain: TerrainMap, route: Route, turn_rate: float) -> float:
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
            f"cannot recover the planning speed from route.duration_s={route.duration_s!r} s (turning time "
            f"{turning_s!r} s at turn_rate_radps={turn_rate!r}); pass speed_mps or cost"
        )
    return speed


# ------------------------------------------------------------------ the mission
def simulate_mission(
    terrain: TerrainMap,
    route: Route,
    robot: RobotParams,
    battery: Battery,
    truth: TruthSimulator | InteractionLog,
    cost: EnergyCost | None = None,
    *,
    speed_mps: float | None = None,
    accel_mps2: float = DEFAULT_ACCEL_MPS2,
    turn_rate_radps: float | None = None,
    yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2,
    start_heading_rad: float | None = None,
    current_convention: str = "motor",
    electronics: bool = True,
    waypoint_tolerance_m: float | None = None,
    stop_at_reserve: bool = False,
    seed: int | None = None,
) -> MissionResult:
    """Drive a route (or replay a log that drove it) and account its energy against a battery.

    Parameters
    ----------
    terrain : TerrainMap
        The map of the route.
    route : Route
        A found route (``exact`` or ``approximate``).
    robot : RobotParams
        The robot that drives (for a TruthSimulator normally ``truth.robot``): its turn
        rate, and the motor constants and electronics that turn the logged currents into
        battery power (:func:`energy.log_battery_power_w`).
    battery : Battery
        Capacity, voltage, reserve and initial state of charge.
    truth : TruthSimulator or InteractionLog
        A truth simulator to drive the route with (its ``run_drive``: it looks up the
        ground and slope along the path), or a recorded log of the route to replay. A log
        with ``pose_xyh`` is mapped onto the route's segments by its pose and must reach
        the route's end (within ``waypoint_tolerance_m``); a log without pose is taken to
        follow this function's velocity profile from its first sample and must last as
        long as the profile.
    cost : EnergyCost, optional
        Edge costs to predict the energy per segment with (e.g. another model's costs than
        the ones that planned the route); ``None`` uses the route's own energies. Its
        speed and turn rate are the profile's defaults.
    speed_mps : float, optional
        Cruise speed (m/s); default ``cost.speed_mps``, else the route's planning speed
        recovered from ``route.duration_s`` (its surface length over its driving time).
    accel_mps2, yaw_accel_radps2 : float
        Acceleration limits of the profile (> 0).
    turn_rate_radps : float, optional
        Pivot yaw rate (rad/s); default ``cost.turn_rate_radps``, else
        ``robot.turn_rate_radps``.
    start_heading_rad : float, optional
        Heading at the start; ``None`` starts facing the first segment. An initial turn is
        driven (and booked to segment 0) but not predicted.
    current_convention : {"motor", "battery"}
        What the logged side currents measure (see :func:`energy.log_battery_power_w`).
    electronics : bool
        Add the robot's sensor and control-board power to the logged drive power (keep it
        equal to whether the planning model includes them).
    waypoint_tolerance_m : float, optional
        How close to a segment's end (and to the goal) a logged pose must come (m);
        default half a map cell.
    stop_at_reserve : bool
        End the series at the first sample below the reserve (the mission is aborted
        there) instead of driving the whole route.
    seed : int, optional
        Seed of the truth simulator for this drive (default: the simulator's own).

    Returns
    -------
    MissionResult

    Raises
    ------
    InvalidParameterError
        Wrong argument types; a route that was not found; bad profile values; a route
        crossing a blocked cell of ``cost``.
    OutOfBoundsError
        A waypoint (or a logged pose) outside the map.
    GridMismatchError
        ``cost`` was built on another grid than ``terrain``.
    DataError
        A replayed log shorter than the route (it does not reach the goal, or lasts less
        than the profile).
    UnknownNameError
        ``current_convention`` unknown; the simulator meets a ground it does not know.
    BlockedPositionError
        The simulator's path crosses an obstacle.

    Examples
    --------
    Usage (needs data or fitted models, so not run as a doctest)::

        result = simulate_mission(tmap, route, robot, Battery(20.0, 24.0), truth=sim)
        print(result.status, result.budget.error_pct)
    """
    # ---------------------------------------------------------------- validation
    if not isinstance(terrain, TerrainMap):
        raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
    if not isinstance(route, Route):
        raise InvalidParameterError(f"route must be a Route, got {type(route).__name__!r}")
    if not route.found:
        raise InvalidParameterError(f"route has status {route.status!r} and no waypoints; expected a found route")
    if not isinstance(robot, RobotParams):
        raise InvalidParameterError(f"robot must be a RobotParams, got {type(robot).__name__!r}")
    if not isinstance(battery, Battery):
        raise InvalidParameterError(f"battery must be a Battery, got {type(battery).__name__!r}")
    if not isinstance(truth, (TruthSimulator, InteractionLog)):
        raise InvalidParameterError(
            f"truth must be a TruthSimulator or an InteractionLog, got {type(truth).__name__!r}"
        )
    if cost is not None and not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost or None, got {type(cost).__name__!r}")
    if current_convention not in CURRENT_CONVENTIONS:
        raise UnknownNameError(f"current_convention must be one of {CURRENT_CONVENTIONS!r}, got {current_convention!r}")
    wp = route.waypoints_m
    inside = np.asarray(terrain.contains(wp[:, 0], wp[:, 1]))
    if not np.all(inside):
        bad = wp[~inside][0]
        raise OutOfBoundsError(
            f"route waypoint {tuple(bad.tolist())!r} m lies outside the map bounds {terrain.bounds!r}"
        )
    if cost is not None and not cost.terrain.same_grid(terrain):
        raise GridMismatchError(
            f"cost was built on a grid of shape {cost.shape!r}, cell {cost.terrain.cell_size_m!r} m, origin "
            f"{cost.terrain.origin_xy_m!r}; terrain has {terrain.shape!r}, {terrain.cell_size_m!r} m, "
            f"{terrain.origin_xy_m!r}"
        )
    if turn_rate_radps is None:
        turn_rate_radps = cost.turn_rate_radps if cost is not None else robot.turn_rate_radps
    turn_rate = _real("turn_rate_radps", turn_rate_radps, low=0.0)
    if speed_mps is None:
        speed = cost.speed_mps if cost is not None else _route_speed_mps(terrain, route, turn_rate)
    else:
        speed = _real("speed_mps", speed_mps, low=0.0)
    accel = _real("accel_mps2", accel_mps2, low=0.0)
    yaw_accel = _real("yaw_accel_radps2", yaw_accel_radps2, low=0.0)
    tol = terrain.cell_size_m / 2.0 if waypoint_tolerance_m is None else _real(
        "waypoint_tolerance_m", waypoint_tolerance_m, low=0.0, low_open=False)
    if start_heading_rad is not None:
        start_heading_rad = _real("start_heading_rad", start_heading_rad)
    if not isinstance(stop_at_reserve, bool):
        raise InvalidParameterError(f"stop_at_reserve must be a bool, got {stop_at_reserve!r}")

    # ---------------------------------------------------------------- prediction
    if cost is None:
        straight_pred, turn_pred = route.segment_energy_j, route.turn_energy_j[:-1]
    else:
        straight_pred = cost.segment_energy_j(wp[:-1], wp[1:])
        turn_pred = cost.turn_energies_j(wp)[1][:-1]
    seg_pred = straight_pred + turn_pred
    if not np.all(np.isfinite(seg_pred)):
        i = int(np.flatnonzero(~np.isfinite(seg_pred))[0])
        raise InvalidParameterError(
            f"route segment {i} from {tuple(wp[i].tolist())!r} to {tuple(wp[i + 1].tolist())!r} m crosses a "
            "blocked cell of cost; expected a route valid for cost"
        )
    pts, kept = _drivable_waypoints(route.waypoints_m)
    turn_s, straight_s = _planned_durations_s(pts, start_heading_rad, speed, accel, turn_rate, yaw_accel)

    # ---------------------------------------------------------------- drive or replay
    truth_power = None
    if isinstance(truth, TruthSimulator):
        profile = drive_profile(pts, speed, accel_mps2=accel, turn_rate_radps=turn_rate, yaw_accel_radps2=yaw_accel,
                                dt_s=1.0 / truth.current_rate_hz, start_heading_rad=start_heading_rad)
        run = truth.run_drive(terrain, profile, seed=seed)
        log = run.log
        truth_power = np.asarray(run.breakdown.total_power_w)
        source = "truth"
    else:
        log = truth
        source = "replay"
    t = log.time_s - log.time_s[0]
    if len(log) < 2:
        raise DataError(f"the log has {len(log)} drive sample(s); a mission needs at least 2")

    if log.pose_xyh is not None:
        xy = np.asarray(log.pose_xyh[:, :2])
        terrain.rowcol(xy[:, 0], xy[:, 1])  # OutOfBoundsError for poses off the map
        heading = np.asarray(log.pose_xyh[:, 2])
        sub, reached = _segments_by_pose(xy, pts, tol)
        n_sub = pts.shape[0] - 1
        end_gap = float(np.hypot(*(xy[-1] - pts[-1])))
        if reached < n_sub or end_gap > tol:
            raise DataError(
                f"the log ends {end_gap:.3f} m from the route's goal {tuple(pts[-1].tolist())!r} after reaching "
                f"{reached} of {n_sub} segment ends (tolerance {tol!r} m); expected a log of the whole route"
            )
    else:
        ends = np.cumsum(turn_s + straight_s)
        t_end = float(ends[-1])
        sub = np.minimum(np.searchsorted(ends, t, side="right"), ends.size - 1)
        if t[-1] < t_end - 1.0 / log.drive_rate_hz - 1e-9:
            raise DataError(
                f"the log lasts {float(t[-1])!r} s but driving the route takes {t_end!r} s at speed_mps={speed!r}; "
                "expected a log of the whole route"
            )
        rate = log.drive_rate_hz
        profile = drive_profile(pts, speed, accel_mps2=accel, turn_rate_radps=turn_rate, yaw_accel_radps2=yaw_accel,
                                dt_s=1.0 / rate, start_heading_rad=start_heading_rad)
        ppose = np.asarray(profile.pose_xyh)
        pt = np.asarray(profile.time_s)
        xy = np.column_stack([np.interp(t, pt, ppose[:, 0]), np.interp(t, pt, ppose[:, 1])])
        h = np.interp(t, pt, np.unwrap(ppose[:, 2]))
        heading = np.pi - np.mod(np.pi - h, 2.0 * np.pi)
    seg_index = kept[sub]

    # ---------------------------------------------------------------- energy
    power = log_battery_power_w(log, robot, current_convention=current_convention, electronics=electronics)
    discharge = discharge_from_power(battery, t, power)
    end = len(log)
    aborted = False
    if stop_at_reserve and discharge.reserve_crossed_index is not None:
        end = max(discharge.reserve_crossed_index + 1, 2)
        aborted = end < len(log)
        if aborted:
            discharge = discharge_from_power(battery, t[:end], power[:end])
            log = log.slice(float(log.time_s[0]), float(log.time_s[end]))  # the part driven
    sl = slice(0, end)
    si = seg_index[sl]
    ts = t[sl]

    # Predicted cumulative energy: from a segment's first sample, its turn's prediction accrues
    # linearly over the planned turn time, then its straight's over the planned straight time
    # (segment indices never decrease along a log).
    run_start = np.concatenate(([True], si[1:] != si[:-1]))
    elapsed = ts - ts[run_start][np.cumsum(run_start) - 1]
    plan_turn = np.zeros(seg_pred.size)
    plan_straight = np.zeros(seg_pred.size)
    plan_turn[kept], plan_straight[kept] = turn_s, straight_s

    def _ramp(x: np.ndarray, span: np.ndarray) -> np.ndarray:
        return np.where(span > 0, np.clip(x / np.where(span > 0, span, 1.0), 0.0, 1.0), 1.0)

    accrued = (turn_pred[si] * _ramp(elapsed, plan_turn[si])
               + straight_pred[si] * _ramp(elapsed - plan_turn[si], plan_straight[si]))
    predicted_cum_j = np.concatenate(([0.0], np.cumsum(seg_pred)))[si] + accrued

    # An aborted mission's budget covers the part driven: full predictions of the segments it
    # left, the accrued prediction of the one it stopped in, nothing for the rest.
    seg_budget = seg_pred
    if aborted:
        seg_budget = np.where(np.arange(seg_pred.size) < si[-1], seg_pred, 0.0)
        seg_budget[si[-1]] = accrued[-1]
    budget = energy_budget(discharge, float(seg_budget.sum()), segment_index=si, segment_predicted_j=seg_budget)
    truth_energy_j = math.nan
    if truth_power is not None:
        tp = truth_power[sl]
        truth_energy_j = float(np.sum(0.5 * (tp[1:] + tp[:-1]) * np.diff(ts)))

    cross_t = discharge.reserve_crossed_time_s
    cross_xy = None
    cross_seg = None
    if cross_t is not None:
        k = discharge.reserve_crossed_index
        cross_xy = (float(np.interp(cross_t, t[sl], xy[sl, 0])), float(np.interp(cross_t, t[sl], xy[sl, 1])))
        cross_seg = int(seg_index[max(k - 1, 0)])

    return MissionResult(
        status="completed" if budget.feasible else "reserve_violated",
        source=source,
        route=route,
        budget=budget,
        time_s=t[sl],
        x_m=xy[sl, 0],
        y_m=xy[sl, 1],
        heading_rad=heading[sl],
        v_mps=log.v_mps[sl],
        omega_radps=log.omega_radps[sl],
        current_left_a=log.current_left_a[sl],
        current_right_a=log.current_right_a[sl],
        power_w=power[sl],
        battery_current_a=discharge.current_a,
        energy_wh=discharge.energy_wh,
        predicted_energy_wh=predicted_cum_j / 3600.0,
        charge_mah=discharge.charge_mah,
        soc=discharge.soc,
        segment_index=seg_index[sl],
        reserve_crossed_time_s=cross_t,
        reserve_crossed_xy_m=cross_xy,
        reserve_crossed_segment=cross_seg,
        speed_mps=speed,
        accel_mps2=accel,
        turn_rate_radps=turn_rate,
        yaw_accel_radps2=yaw_accel,
        current_convention=current_convention,
        truth_energy_j=truth_energy_j,
        log=log,
    )
