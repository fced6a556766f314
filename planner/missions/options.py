"""How a mission is driven and booked: one frozen, checked value per group of options that travel together."""

from __future__ import annotations

from dataclasses import dataclass

from energy.budget import CURRENT_CONVENTIONS
from energy.profiles import DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2
from terrawatt_base.checks import check_bool, check_choice, check_optional_real, check_real, check_seed

__all__ = ["MISSION_FORECASTS", "MissionDrive", "MissionAccounting"]

#: How a mission's energy is predicted (:class:`MissionAccounting`).
MISSION_FORECASTS = ("auto", "profile", "edges")


@dataclass(frozen=True, kw_only=True)
class MissionDrive:
    """How one route is driven: its stop-turn-go velocity profile, where it stops, the simulated drive's seed.

    Parameters
    ----------
    speed_mps : float, optional
        Cruise speed (m/s, > 0); default the cost's speed, else the route's planning speed
        recovered from ``route.duration_s`` (its surface length over its driving time).
    accel_mps2, yaw_accel_radps2 : float
        Acceleration limits of the profile (> 0).
    turn_rate_radps : float, optional
        Pivot yaw rate (rad/s, > 0); default the cost's, else the robot's.
    start_heading_rad : float, optional
        Heading at the start; ``None`` starts facing the first segment. An initial turn is
        driven (and booked to segment 0) but not predicted.
    waypoint_tolerance_m : float, optional
        How close to a segment's end (and to the goal) a logged pose must come (m, >= 0);
        default half a map cell.
    stop_at_reserve : bool
        End the drive at the first sample below the battery's reserve (the mission is aborted
        there) instead of driving the whole route.
    seed : int, optional
        Seed of the truth simulator for this drive (default: the simulator's own).

    Raises
    ------
    InvalidParameterError
        A value of the wrong type or out of range (the message names it).

    Examples
    --------
    >>> MissionDrive(speed_mps=0.8, stop_at_reserve=True).speed_mps
    0.8
    """

    speed_mps: float | None = None
    accel_mps2: float = DEFAULT_ACCEL_MPS2
    turn_rate_radps: float | None = None
    yaw_accel_radps2: float = DEFAULT_YAW_ACCEL_RADPS2
    start_heading_rad: float | None = None
    waypoint_tolerance_m: float | None = None
    stop_at_reserve: bool = False
    seed: int | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        positive = {"low": 0.0, "low_inclusive": False}
        set_(self, "speed_mps", check_optional_real("speed_mps", self.speed_mps, **positive))
        set_(self, "accel_mps2", check_real("accel_mps2", self.accel_mps2, **positive))
        set_(self, "turn_rate_radps", check_optional_real("turn_rate_radps", self.turn_rate_radps, **positive))
        set_(self, "yaw_accel_radps2", check_real("yaw_accel_radps2", self.yaw_accel_radps2, **positive))
        set_(self, "start_heading_rad", check_optional_real("start_heading_rad", self.start_heading_rad))
        set_(self, "waypoint_tolerance_m", check_optional_real("waypoint_tolerance_m", self.waypoint_tolerance_m,
                                                               low=0.0))
        set_(self, "stop_at_reserve", check_bool("stop_at_reserve", self.stop_at_reserve))
        set_(self, "seed", check_seed(self.seed))


@dataclass(frozen=True, kw_only=True)
class MissionAccounting:
    """How a drive's energy is booked: the logged currents turned into battery power, and the prediction beside it.

    Parameters
    ----------
    current_convention : {"motor", "battery"}
        What the logged side currents measure (see :func:`energy.budget.log_battery_power_w`).
    electronics : bool
        Add the robot's sensor and control-board power to the logged drive power (keep it
        equal to whether the planning model includes them).
    current_offset_a : float, optional
        The rest offset of the current sensor that logged the drive (A, >= 0): logged, never
        paid, so removed before the currents become battery power. ``None``: the truth
        simulator's own sensor (``truth.noise.current_offset_a``), or for a replayed log the
        robot's ``rest_current_a``.
    forecast : {"auto", "profile", "edges"}
        The predicted energy: ``"profile"`` prices the whole stop-turn-go profile (ramps,
        pivots, the electronics over the longer drive) with the physics model that priced the
        cost (:func:`planner.route_price.profile_forecast_w`); ``"edges"`` adds up the route's
        (or the cost's) segment and turn energies, steady driving at the planning speed;
        ``"auto"`` (default): ``"profile"`` where the cost has a physics model, else ``"edges"``.

    Raises
    ------
    InvalidParameterError, UnknownNameError
        A bad flag or offset; an unknown convention or forecast (the message names it).

    Examples
    --------
    >>> MissionAccounting(forecast="edges").current_convention
    'motor'
    """

    current_convention: str = "motor"
    electronics: bool = True
    current_offset_a: float | None = None
    forecast: str = "auto"

    def __post_init__(self) -> None:
        check_choice("current_convention", self.current_convention, CURRENT_CONVENTIONS)
        check_choice("forecast", self.forecast, MISSION_FORECASTS)
        object.__setattr__(self, "electronics", check_bool("electronics", self.electronics))
        object.__setattr__(self, "current_offset_a",
                           check_optional_real("current_offset_a", self.current_offset_a, low=0.0))
