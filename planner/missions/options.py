"""How a mission is driven and booked: one frozen, checked value per group of options that travel together."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import KW_ONLY, dataclass

from energy import GroundParams, RobotParams
from energy.budget import CURRENT_CONVENTIONS
from energy.params import robot_params
from energy.profiles import DEFAULT_ACCEL_MPS2, DEFAULT_YAW_ACCEL_RADPS2
from terrawatt_base.checks import (
    check_bool,
    check_choice,
    check_instance,
    check_int,
    check_optional_real,
    check_real,
    check_seed,
)
from terrawatt_base.errors import InvalidParameterError

from .monte_carlo_model import MC_DRAW_MODES
from .monte_carlo_sampling import MissionDistributions

__all__ = ["MISSION_FORECASTS", "DEFAULT_MC_CURRENT_RATE_HZ", "MissionDrive", "MissionAccounting", "MonteCarloStudy",
           "MissionTruth"]

#: Current sampling rate (Hz) of the truth simulator of each Monte Carlo mission: a mission's
#: energy moves by < 0.2 % from 100 Hz (its P50/P90/P99 by ~0.1 %), at a quarter of the work.
DEFAULT_MC_CURRENT_RATE_HZ = 20.0

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
    stops : tuple of int
        Indices of the route's waypoints the robot stops at whatever its heading there (e.g. a
        tour's sites, :func:`planner.tours.simulate_tours_mc`): it stops and goes again even where
        it leaves on the heading it arrived on, where it would otherwise drive through
        (:data:`energy.profiles.COLLINEAR_TOL_RAD`). Default none: it stops only where it turns.
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
    stops: tuple[int, ...] = ()
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
        try:
            stops = tuple(sorted({check_int("stops", k, low=0) for k in self.stops}))
        except TypeError:
            raise InvalidParameterError(f"stops must be waypoint indices, got {self.stops!r:.80}",
                                        parameter="stops") from None
        set_(self, "stops", stops)
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


@dataclass(frozen=True)
class MonteCarloStudy:
    """How many missions a Monte Carlo study drives, what they draw, from which seed, and the risk it accepts.

    Parameters
    ----------
    n : int
        Number of missions (>= 1).
    seed : int or None
        Seed of the whole study (``None``: a fresh one, kept in ``result.entropy``: pass it
        as ``seed`` to repeat the study).
    draw_from : {"parameters", "model"}
        ``"parameters"`` (default): each mission draws :class:`MissionDistributions` and
        drives the route against a truth simulation. ``"model"``: each mission draws one
        factor per ground from the planning model's own predictive distribution (standard
        normal, Student-t on a ground the model never drove) and prices every edge at
        ``mean + z_ground * sd`` (:mod:`planner.missions.monte_carlo_model`).
    distributions : MissionDistributions, optional
        Ranges of the drawn parameters with ``draw_from="parameters"`` (default
        :class:`MissionDistributions`); ``draw_from="model"`` takes none.
    chunk_size : int
        Missions per dask task (>= 1); does not change the result.
    max_risk_pct : float
        Most missions (%, in [0, 100]) below the reserve for :attr:`MonteCarloResult.ok`.

    Raises
    ------
    InvalidParameterError
        ``n < 1``; a bad seed, chunk size or risk; ``draw_from`` unknown; distributions with
        ``draw_from="model"`` (the message names the parameter).

    Examples
    --------
    >>> MonteCarloStudy(200, seed=1).chunk_size
    8
    """

    n: int
    _: KW_ONLY
    seed: int | None = 0
    draw_from: str = "parameters"
    distributions: MissionDistributions | None = None
    chunk_size: int = 8
    max_risk_pct: float = 5.0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "n", check_int("n", self.n, low=1))
        set_(self, "seed", check_seed(self.seed))
        if self.draw_from not in MC_DRAW_MODES:
            raise InvalidParameterError(f"draw_from must be one of {MC_DRAW_MODES!r}, got {self.draw_from!r}",
                                        parameter="draw_from")
        if self.draw_from == "model" and self.distributions is not None:
            raise InvalidParameterError("distributions are the typed ranges of draw_from='parameters'; "
                                        "draw_from='model' draws from the model and takes none",
                                        parameter="distributions")
        if self.distributions is not None:
            check_instance("distributions", self.distributions, MissionDistributions)
        set_(self, "chunk_size", check_int("chunk_size", self.chunk_size, low=1))
        set_(self, "max_risk_pct", check_real("max_risk_pct", self.max_risk_pct, low=0.0, high=100.0))


@dataclass(frozen=True, kw_only=True)
class MissionTruth:
    """The nominal robot a Monte Carlo study's truth simulator drives: robot, grounds, speed and sampling rate.

    Parameters
    ----------
    robot : RobotParams or str
        The robot (or a preset name, or a robot file), before payload; held as ``RobotParams``.
    grounds : mapping of str to GroundParams, optional
        Nominal parameters of the map's grounds; default the presets of their names.
    speed_mps : float, optional
        Nominal driving speed (m/s, > 0); default the route's planning speed.
    current_rate_hz : float
        Sampling rate of each simulated mission (Hz, > 0).

    Raises
    ------
    InvalidParameterError, UnknownNameError
        A bad speed or rate; grounds that are not a mapping of names to ``GroundParams``; an
        unknown robot preset.

    Examples
    --------
    >>> MissionTruth(speed_mps=0.8).robot.name
    'husky'
    """

    robot: RobotParams | str = "husky"
    grounds: Mapping[str, GroundParams] | None = None
    speed_mps: float | None = None
    current_rate_hz: float = DEFAULT_MC_CURRENT_RATE_HZ

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "robot", robot_params(self.robot))
        grounds = self.grounds
        if grounds is not None and (not isinstance(grounds, Mapping)
                                    or not all(isinstance(g, GroundParams) for g in grounds.values())):
            raise InvalidParameterError(f"grounds must be a mapping of ground name to GroundParams, got {grounds!r:.80}",
                                        parameter="grounds")
        set_(self, "speed_mps", check_optional_real("speed_mps", self.speed_mps, low=0.0, low_inclusive=False))
        set_(self, "current_rate_hz", check_real("current_rate_hz", self.current_rate_hz, low=0.0,
                                                 low_inclusive=False))
