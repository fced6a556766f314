"""The physics forecast of a mission: the planning model over the whole stop-turn-go profile.

Edge costs price steady driving at the planning speed plus turns in place; a driven route
also starts and stops at every waypoint, pivots with a trapezoidal yaw rate and spends the
extra seconds of those ramps with its electronics on. :func:`profile_forecast_w` prices that
profile with the very physics model (robot, effects, ground parameters) that priced the
cost's tables, on the map's ground and slope under every pose (the rule of
:func:`energy.profiles.terrain_along`, which the truth simulator uses too), and
:func:`segment_forecasts_j` splits it into the turn and the straight of each route segment,
the way :func:`planner.simulate_mission` books them.
"""

from __future__ import annotations

import numpy as np

from energy import CommandProfile, drive_profile
from energy.profiles import DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2, terrain_along
from terrawatt_base.errors import InvalidParameterError

from ..edge_cost import EnergyCost
from ..route import Route

__all__ = ["profile_forecast_w", "segment_forecasts_j", "route_forecast_j"]

#: Time step (s) of the profile a forecast prices.
FORECAST_DT_S = 0.05


def profile_forecast_w(cost: EnergyCost, profile: CommandProfile) -> np.ndarray:
    """Battery power (W) at every sample of a command profile, by the physics model that priced ``cost``.

    Parameters
    ----------
    cost : EnergyCost
        Built by :meth:`EnergyCost.from_model` (or ``from_presets``) with a
        :class:`energy.PhysicsEnergyModel`.
    profile : CommandProfile
        Commands with poses on ``cost``'s map (e.g. :func:`energy.drive_profile`).

    Returns
    -------
    numpy.ndarray, shape (N,)

    Raises
    ------
    InvalidParameterError
        A cost without a physics model, a profile without poses.
    OutOfBoundsError
        A pose off the map.
    """
    if not isinstance(cost, EnergyCost) or cost.physics_model is None or cost.ground_params is None:
        raise InvalidParameterError("cost carries no physics model (build it with EnergyCost.from_model and a "
                                    "PhysicsEnergyModel, or from_presets) to forecast a profile with")
    if not isinstance(profile, CommandProfile) or profile.pose_xyh is None:
        raise InvalidParameterError("profile must be a CommandProfile with poses (pose_xyh)")
    t = np.asarray(profile.time_s, dtype=np.float64)
    v = np.asarray(profile.v_mps, dtype=np.float64)
    w = np.asarray(profile.omega_radps, dtype=np.float64)
    pose = np.asarray(profile.pose_xyh, dtype=np.float64)
    rows, cols, slope, _ = terrain_along(cost.terrain, pose[:, 0], pose[:, 1], pose[:, 2])
    ground_index = np.asarray(cost.ground_rows)[rows, cols]
    res = cost.physics_model.power(v, w, list(cost.ground_params), accel_mps2=np.gradient(v, t),
                                   alpha_radps2=np.gradient(w, t), slope_rad=slope, time_s=t,
                                   ground_index=ground_index)
    return np.asarray(res.total_power_w, dtype=np.float64)


def segment_forecasts_j(time_s: np.ndarray, power_w: np.ndarray, turn_s: np.ndarray,
                        straight_s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The energy (J) of the turn and of the straight of each drivable segment of a profile.

    ``turn_s`` / ``straight_s`` are the planned durations
    (:func:`energy.profiles.planned_durations_s`) in the order the profile drives them;
    the power is integrated (trapezoid) between those time marks.

    Examples
    --------
    >>> t = np.linspace(0.0, 3.0, 31)
    >>> turn, straight = segment_forecasts_j(t, np.full(31, 2.0), np.array([1.0]), np.array([2.0]))
    >>> [round(float(turn[0]), 9), round(float(straight[0]), 9)]
    [2.0, 4.0]
    """
    t = np.asarray(time_s, dtype=np.float64) - float(time_s[0])
    p = np.asarray(power_w, dtype=np.float64)
    cumulative = np.concatenate(([0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(t))))
    marks = np.concatenate(([0.0], np.cumsum(np.column_stack([turn_s, straight_s]).ravel())))
    parts = np.diff(np.interp(marks, t, cumulative))
    return parts[0::2], parts[1::2]


def route_forecast_j(cost: EnergyCost, route: Route, *, speed_mps: float | None = None,
                     accel_mps2: float = DEFAULT_ACCEL_MPS2, turn_rate_radps: float | None = None,
                     yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2) -> float:
    """Forecast battery energy (J) of driving ``route`` stop-turn-go, by the physics model that priced ``cost``.

    The profile of :func:`planner.simulate_mission` (:func:`energy.drive_profile` at
    ``speed_mps``, default ``cost.speed_mps``, and ``turn_rate_radps``, default
    ``cost.turn_rate_radps``) priced by :func:`profile_forecast_w`.

    Raises
    ------
    InvalidParameterError
        A cost without a physics model, a route that was not found, bad profile values.
    """
    if not isinstance(route, Route) or not route.found:
        raise InvalidParameterError("route must be a found Route")
    profile = drive_profile(route.waypoints_m, cost.speed_mps if speed_mps is None else speed_mps,
                            turn_rate_radps=cost.turn_rate_radps if turn_rate_radps is None else turn_rate_radps,
                            dt_s=FORECAST_DT_S, accel_mps2=accel_mps2, yaw_accel_radps2=yaw_accel_radps2)
    power = profile_forecast_w(cost, profile)
    t = np.asarray(profile.time_s, dtype=np.float64)
    return float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(t)))
