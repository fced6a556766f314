"""Mission simulation: drive a route against a truth simulator or a recorded log, with an energy budget.

:func:`simulate_mission` turns a :class:`~planner.route.Route` into a drivable velocity
profile, drives it (or replays a log that drove it) and returns a :class:`MissionResult`:
the time series (pose, speeds, side currents, battery power, cumulative Wh and mAh, state of
charge, route segment) and an :class:`~energy.budget.EnergyBudget` comparing the predicted
energy with the actual one, with the reserve at arrival, the feasibility against the
battery and a per-segment breakdown.

Velocity profile (stop-turn-go, :func:`energy.drive_profile`): at every waypoint the
robot stops and pivots in place to the next segment's heading at the turn rate (trapezoidal
yaw rate, ``yaw_accel_radps2``), then drives the segment from rest to rest at the planning
speed (trapezoidal speed, ``accel_mps2``). This is the motion the planner's costs price:
straight segments at the planning speed plus turns in place at the waypoints. Turning
smoothly (arcs) is not modelled.

Segments: the turn at waypoint ``k`` belongs to segment ``k`` (the one it starts), as in
``Route.turn_energy_j``; so the predicted energy of segment ``k`` is
``segment_energy_j[k] + turn_energy_j[k]`` (the last segment also holds the stop at the
last waypoint) and the segments add up to ``Route.energy_j``. A waypoint the robot drives
through (no heading change, :func:`energy.profiles.drivable_waypoints`) does not split the
drive: the route segments it joins are booked, and predicted, as one, on the first of them.
A waypoint of ``drive.stops`` is stopped at whatever the heading (a tour's site): it splits the
drive there, and the profile forecast prices its stop-and-go (the edges' forecast has no turn there
to price: ``forecast="edges"`` leaves it out).
Driven samples are assigned to segments from the log's pose (each segment ends at the
robot's closest approach to its end waypoint once it is within ``waypoint_tolerance_m``
along the segment); a log without a pose is assumed to follow the velocity profile from its
first sample and is assigned by time.

Actual power: :func:`energy.budget.log_battery_power_w` on the driven log (drive power from the
logged side currents, less the current sensor's rest offset, plus the robot's electronics),
so driving with a :class:`~energy.sim.TruthSimulator` and replaying the log it produced
(with the same ``current_offset_a``) give the same result, and the actual energy is booked
like the physics model that priced the route. The sensor's offset is logged, never paid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from energy import (
    Battery,
    InteractionLog,
    RobotParams,
    TruthSimulator,
    discharge_from_power,
    drive_profile,
    energy_budget,
)
from energy.battery import Discharge
from energy.budget import log_battery_power_w
from energy.profiles import drivable_waypoints, planned_durations_s
from terrain import TerrainMap
from terrawatt_base.checks import check_instance, check_real, fmt_number
from terrawatt_base.errors import DataError, GridMismatchError, InvalidParameterError, OutOfBoundsError

from ..edge_cost import EnergyCost
from ..route import Route
from ..route_price import FORECAST_DT_S, profile_forecast_w, segment_forecasts_j
from .options import MissionAccounting, MissionDrive
from .results import MissionResult
from .tracking import route_speed_mps, segments_by_pose

__all__ = ["simulate_mission"]


@dataclass(frozen=True)
class _Profile:
    """The checked velocity profile of one mission."""

    speed_mps: float
    accel_mps2: float
    turn_rate_radps: float
    yaw_accel_radps2: float
    tolerance_m: float
    start_heading_rad: float | None

    def commands(self, points_m: np.ndarray, dt_s: float):  # -> energy.CommandProfile
        """The commands along drivable waypoints (:func:`energy.profiles.drivable_waypoints`, the stops kept): the
        robot stops at every one of them."""
        return drive_profile(points_m, self.speed_mps, accel_mps2=self.accel_mps2,
                             turn_rate_radps=self.turn_rate_radps, yaw_accel_radps2=self.yaw_accel_radps2,
                             dt_s=dt_s, start_heading_rad=self.start_heading_rad,
                             stops=np.arange(1, points_m.shape[0] - 1))


def simulate_mission(
    terrain: TerrainMap,
    route: Route,
    robot: RobotParams,
    battery: Battery,
    truth: TruthSimulator | InteractionLog,
    cost: EnergyCost | None = None,
    *,
    drive: MissionDrive | None = None,
    accounting: MissionAccounting | None = None,
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
        battery power (:func:`energy.budget.log_battery_power_w`).
    battery : Battery
        Capacity, voltage, reserve and initial state of charge.
    truth : TruthSimulator or InteractionLog
        A truth simulator to drive the route with (its ``run_drive``: it looks up the
        ground and slope along the path), or a recorded log of the route to replay. A log
        with ``pose_xyh`` is mapped onto the route's segments by its pose and must reach
        the route's end (within ``drive.waypoint_tolerance_m``); a log without pose is taken
        to follow this function's velocity profile from its first sample and must last as
        long as the profile.
    cost : EnergyCost, optional
        Edge costs to predict the energy per segment with (e.g. another model's costs than
        the ones that planned the route); ``None`` uses the route's own energies. Its
        speed and turn rate are the profile's defaults.
    drive : MissionDrive, optional
        The velocity profile (speed, accelerations, turn rate, start heading), the waypoint
        tolerance, whether to stop at the reserve and the simulated drive's seed
        (:class:`planner.missions.options.MissionDrive`; default ``MissionDrive()``).
    accounting : MissionAccounting, optional
        What the logged currents measure, the electronics, the current sensor's offset and how
        the energy is predicted (:class:`planner.missions.options.MissionAccounting`; default
        ``MissionAccounting()``): ``forecast="profile"`` needs a cost with a physics model.

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

        result = simulate_mission(tmap, route, robot, Battery(20.0, 24.0), truth=sim,
                                  drive=MissionDrive(stop_at_reserve=True))
        print(result.status, result.budget.error_pct)
    """
    # the named steps below run in this order; each checks what it is given
    drive = MissionDrive() if drive is None else check_instance("drive", drive, MissionDrive)
    accounting = MissionAccounting() if accounting is None else check_instance("accounting", accounting,
                                                                               MissionAccounting)
    _check_inputs(terrain, route, robot, battery, truth, cost)
    forecast = accounting.forecast
    if forecast == "profile" and (cost is None or cost.physics_model is None):
        raise InvalidParameterError("forecast='profile' needs a cost built with a PhysicsEnergyModel "
                                    "(CostSpec.build on the robot's physics); use forecast='edges'",
                                    parameter="accounting.forecast")
    prof = _profile(terrain, route, robot, cost, drive)
    straight_pred, turn_pred = _segment_predictions(route, cost)
    if drive.stops and drive.stops[-1] >= len(route.waypoints_m):
        raise InvalidParameterError(f"drive.stops must be indices of the route's {len(route.waypoints_m)} "
                                    f"waypoints, got {drive.stops!r}", parameter="drive.stops")
    pts, kept = drivable_waypoints(route.waypoints_m, stops=drive.stops)
    turn_s, straight_s = planned_durations_s(pts, prof.start_heading_rad, prof.speed_mps, prof.accel_mps2,
                                             prof.turn_rate_radps, prof.yaw_accel_radps2)
    if forecast != "edges" and cost is not None and cost.physics_model is not None:
        profile = prof.commands(pts, FORECAST_DT_S)
        turn_kept, straight_kept = segment_forecasts_j(np.asarray(profile.time_s), profile_forecast_w(cost, profile),
                                                       turn_s, straight_s)
        turn_pred, straight_pred = np.zeros_like(turn_pred), np.zeros_like(straight_pred)
        turn_pred[kept], straight_pred[kept] = turn_kept, straight_kept
        forecast = "profile"
    else:
        turn_pred, straight_pred = _fold(turn_pred, kept), _fold(straight_pred, kept)
        forecast = "edges"
    seg_pred = straight_pred + turn_pred

    log, truth_power, source = _drive_or_replay(terrain, truth, pts, prof, drive.seed)
    t = log.time_s - log.time_s[0]
    if len(log) < 2:
        raise DataError(f"the log has {len(log)} drive sample(s); a mission needs at least 2")
    xy, heading, sub = _track(terrain, log, t, pts, turn_s, straight_s, prof)
    seg_index = kept[sub]

    current_offset_a = accounting.current_offset_a
    if current_offset_a is None and isinstance(truth, TruthSimulator):
        current_offset_a = truth.noise.current_offset_a
    power = log_battery_power_w(log, robot, current_convention=accounting.current_convention,
                                electronics=accounting.electronics, current_offset_a=current_offset_a)
    discharge, log, end = _discharge(battery, log, t, power, drive.stop_at_reserve)
    aborted = end < len(t)
    sl = slice(0, end)
    si, ts = seg_index[sl], t[sl]
    predicted_cum_j, accrued = _predicted_cumulative_j(si, ts, kept, turn_s, straight_s, turn_pred, straight_pred)

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
    cross_xy = cross_seg = None
    if cross_t is not None:
        cross_xy = _position_at(cross_t, ts, xy[sl])
        cross_seg = int(seg_index[max(discharge.reserve_crossed_index - 1, 0)])
    empty_t = discharge.depleted_time_s
    empty_xy = None if empty_t is None else _position_at(empty_t, ts, xy[sl])

    return MissionResult(
        status="completed" if budget.feasible else "reserve_violated",
        source=source,
        route=route,
        budget=budget,
        time_s=ts,
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
        segment_index=si,
        reserve_crossed_time_s=cross_t,
        reserve_crossed_xy_m=cross_xy,
        reserve_crossed_segment=cross_seg,
        speed_mps=prof.speed_mps,
        accel_mps2=prof.accel_mps2,
        turn_rate_radps=prof.turn_rate_radps,
        yaw_accel_radps2=prof.yaw_accel_radps2,
        current_convention=accounting.current_convention,
        truth_energy_j=truth_energy_j,
        log=log,
        depleted_time_s=empty_t,
        depleted_xy_m=empty_xy,
        forecast=forecast,
    )


# ------------------------------------------------------------------ the steps
def _check_inputs(terrain: object, route: object, robot: object, battery: object, truth: object,
                  cost: object) -> None:
    """Types, a found route of positive length inside the map, a cost on the map's grid."""
    for name, value, cls in (("terrain", terrain, TerrainMap), ("route", route, Route),
                             ("robot", robot, RobotParams), ("battery", battery, Battery)):
        if not isinstance(value, cls):
            raise InvalidParameterError(f"{name} must be a {cls.__name__}, got {type(value).__name__!r}")
    if not route.found:
        raise InvalidParameterError(f"route has status {route.status!r} and no waypoints; expected a found route")
    if not isinstance(truth, (TruthSimulator, InteractionLog)):
        raise InvalidParameterError(
            f"truth must be a TruthSimulator or an InteractionLog, got {type(truth).__name__!r}"
        )
    if cost is not None and not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost or None, got {type(cost).__name__!r}")
    wp = route.waypoints_m
    if np.all(wp == wp[0]):
        raise InvalidParameterError(
            f"start equals goal: every waypoint of the route lies at {tuple(wp[0].tolist())!r} m; nothing to drive"
        )
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


def _profile(terrain: TerrainMap, route: Route, robot: RobotParams, cost: EnergyCost | None,
             drive: MissionDrive) -> _Profile:
    """The velocity profile: the drive's values, else the cost's, the robot's or the route's."""
    turn_rate = drive.turn_rate_radps
    if turn_rate is None:
        turn_rate = check_real("turn_rate_radps", cost.turn_rate_radps if cost is not None else robot.turn_rate_radps,
                               low=0.0, low_inclusive=False)
    speed = drive.speed_mps
    if speed is None:
        speed = cost.speed_mps if cost is not None else route_speed_mps(route, turn_rate)
    tol = drive.waypoint_tolerance_m
    return _Profile(
        speed_mps=speed,
        accel_mps2=drive.accel_mps2,
        turn_rate_radps=turn_rate,
        yaw_accel_radps2=drive.yaw_accel_radps2,
        tolerance_m=terrain.cell_size_m / 2.0 if tol is None else tol,
        start_heading_rad=drive.start_heading_rad,
    )


def _segment_predictions(route: Route, cost: EnergyCost | None) -> tuple[np.ndarray, np.ndarray]:
    """Predicted energy of each route segment's straight and of the turn that starts it (J)."""
    wp = route.waypoints_m
    if cost is None:
        straight_pred, turns = np.array(route.segment_energy_j, dtype=np.float64), route.turn_energy_j
    else:
        straight_pred = cost.segment_energy_j(wp[:-1], wp[1:])
        turns = cost.turn_energies_j(wp)[1]
    turn_pred = np.array(turns[:-1], dtype=np.float64)
    straight_pred[-1] += turns[-1]  # the stop at the last waypoint ends the last straight
    seg_pred = straight_pred + turn_pred
    if not np.all(np.isfinite(seg_pred)):
        i = int(np.flatnonzero(~np.isfinite(seg_pred))[0])
        raise InvalidParameterError(
            f"route segment {i} from {tuple(wp[i].tolist())!r} to {tuple(wp[i + 1].tolist())!r} m crosses a "
            "blocked cell of cost; expected a route valid for cost"
        )
    return np.asarray(straight_pred, dtype=np.float64), np.asarray(turn_pred, dtype=np.float64)


def _fold(per_segment: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """Route-segment values summed onto the driven segment holding them (index ``kept[i]``; 0 elsewhere)."""
    group = np.maximum(np.searchsorted(kept, np.arange(per_segment.size), side="right") - 1, 0)
    out = np.zeros_like(per_segment)
    np.add.at(out, kept[group], per_segment)
    return out


def _drive_or_replay(terrain: TerrainMap, truth: TruthSimulator | InteractionLog, pts: np.ndarray,
                     prof: _Profile, seed: int | None) -> tuple[InteractionLog, np.ndarray | None, str]:
    """The driven log, the truth's noise-free battery power (None for a replay) and the source."""
    if isinstance(truth, TruthSimulator):
        run = truth.run_drive(terrain, prof.commands(pts, 1.0 / truth.current_rate_hz), seed=seed)
        return run.log, np.asarray(run.breakdown.total_power_w), "truth"
    return truth, None, "replay"


def _track(terrain: TerrainMap, log: InteractionLog, t: np.ndarray, pts: np.ndarray, turn_s: np.ndarray,
           straight_s: np.ndarray, prof: _Profile) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, heading and drivable segment of each sample: from the log's pose, or (a log
    without pose) from the velocity profile by time."""
    tol = prof.tolerance_m
    if log.pose_xyh is not None:
        xy = np.asarray(log.pose_xyh[:, :2])
        terrain.rowcol(xy[:, 0], xy[:, 1])  # OutOfBoundsError for poses off the map
        heading = np.asarray(log.pose_xyh[:, 2])
        sub, reached = segments_by_pose(xy, pts, tol)
        n_sub = pts.shape[0] - 1
        end_gap = float(np.hypot(*(xy[-1] - pts[-1])))
        if reached < n_sub or end_gap > tol:
            raise DataError(
                f"the log ends {end_gap:.3f} m from the route's goal {tuple(pts[-1].tolist())!r} after reaching "
                f"{reached} of {n_sub} segment ends (tolerance {fmt_number(tol)} m); expected a log of the whole route"
            )
        return xy, heading, sub
    ends = np.cumsum(turn_s + straight_s)
    t_end = float(ends[-1])
    sub = np.minimum(np.searchsorted(ends, t, side="right"), ends.size - 1)
    if t[-1] < t_end - 1.0 / log.drive_rate_hz - 1e-9:
        raise DataError(
            f"the log lasts {fmt_number(t[-1])} s but driving the route takes {fmt_number(t_end)} s at "
            f"speed_mps={fmt_number(prof.speed_mps)}; expected a log of the whole route"
        )
    profile = prof.commands(pts, 1.0 / log.drive_rate_hz)
    ppose = np.asarray(profile.pose_xyh)
    pt = np.asarray(profile.time_s)
    xy = np.column_stack([np.interp(t, pt, ppose[:, 0]), np.interp(t, pt, ppose[:, 1])])
    h = np.interp(t, pt, np.unwrap(ppose[:, 2]))
    return xy, np.pi - np.mod(np.pi - h, 2.0 * np.pi), sub


def _discharge(battery: Battery, log: InteractionLog, t: np.ndarray, power: np.ndarray,
               stop_at_reserve: bool) -> tuple[Discharge, InteractionLog, int]:
    """The battery's discharge over the drive, ended at the reserve with ``stop_at_reserve``:
    the discharge, the log of the part driven and its number of samples."""
    discharge = discharge_from_power(battery, t, power)
    end = len(log)
    if stop_at_reserve and discharge.reserve_crossed_index is not None:
        end = max(discharge.reserve_crossed_index + 1, 2)
        if end < len(log):
            discharge = discharge_from_power(battery, t[:end], power[:end])
            log = log.slice(float(log.time_s[0]), float(log.time_s[end]))  # the part driven
    return discharge, log, end


def _predicted_cumulative_j(si: np.ndarray, ts: np.ndarray, kept: np.ndarray, turn_s: np.ndarray,
                            straight_s: np.ndarray, turn_pred: np.ndarray,
                            straight_pred: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Predicted cumulative energy at each sample (J) and the part accrued in its segment.

    From a segment's first sample, its turn's prediction accrues linearly over the planned
    turn time, then its straight's over the planned straight time (segment indices never
    decrease along a log).
    """
    seg_pred = straight_pred + turn_pred
    run_start = np.concatenate(([True], si[1:] != si[:-1]))
    elapsed = ts - ts[run_start][np.cumsum(run_start) - 1]
    plan_turn = np.zeros(seg_pred.size)
    plan_straight = np.zeros(seg_pred.size)
    plan_turn[kept], plan_straight[kept] = turn_s, straight_s

    def ramp(x: np.ndarray, span: np.ndarray) -> np.ndarray:
        return np.where(span > 0, np.clip(x / np.where(span > 0, span, 1.0), 0.0, 1.0), 1.0)

    accrued = (turn_pred[si] * ramp(elapsed, plan_turn[si])
               + straight_pred[si] * ramp(elapsed - plan_turn[si], plan_straight[si]))
    return np.concatenate(([0.0], np.cumsum(seg_pred)))[si] + accrued, accrued


def _position_at(time_s: float, t: np.ndarray, xy: np.ndarray) -> tuple[float, float]:
    """Position at ``time_s``, interpolated along the driven path."""
    return float(np.interp(time_s, t, xy[:, 0])), float(np.interp(time_s, t, xy[:, 1]))
