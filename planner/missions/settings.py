"""Knobs of the adaptive mission loop: :class:`AdaptiveSettings` and the update scopes; where a mission goes
(:class:`MissionGoal`), how its navigator prices and fits models (:class:`NavigatorModels`) and how a recording is fed
to it (:class:`ReplayFeed`)."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from energy import GROUND_PRESETS, GroundParams, ground_preset
from terrain import InvalidParameterError, UnknownNameError
from terrawatt_base.checks import (
    check_bool,
    check_choice,
    check_instance,
    check_int,
    check_real,
    check_seed,
    real_array,
)

from ..learned_cost import LearnedEnergyModel
from ..registry import UpdatePolicy

__all__ = ["UPDATE_SCOPES", "UPDATE_SOURCES", "REPLAY_MODES", "AdaptiveSettings", "MissionGoal", "NavigatorModels",
           "ReplayFeed"]

#: How a recording is fed to a navigator (:class:`ReplayFeed`).
REPLAY_MODES = ("auto", "legs", "drive")

#: Cells an update covers: every cell of the flagged region's ground class served by the same
#: model(s) (``"ground_class"``), or only the flagged cells (``"region"``).
UPDATE_SCOPES = ("ground_class", "region")
#: What a flagged region's new model is fitted on first: an excitation manoeuvre the
#: navigator requests (``"manoeuvre"``; driven data when the robot declines it), or what the
#: robot drove there (``"driven"``; a manoeuvre is requested when that is too little).
UPDATE_SOURCES = ("manoeuvre", "driven")


@dataclass(frozen=True, kw_only=True)
class AdaptiveSettings:
    """Knobs of :func:`run_adaptive_mission`.

    Parameters
    ----------
    speed_mps : float
        Planning and driving speed (m/s, > 0).
    leg_length_m : float
        Length of route driven between comparisons (m, > 0).
    policy : UpdatePolicy
        When a cell's error calls for an update.
    update_scope : {"ground_class", "region"}
        Cells an update covers (see the module docstring).
    planner : str
        Planner name for :func:`plan_route` (default ``"lattice"``).
    planner_time_limit_s : float
        OMPL time budget (s; ignored by the lattice).
    excitation_duration_s, turn_excitation_duration_s : float
        Lengths of the straight and pivot excitation runs (s, > 2).
    excitation_speeds_mps : tuple of float
        Speed levels of the straight excitation run.
    excitation_omega_radps : float
        Pivot rate of the turn excitation run (rad/s, > 0).
    validation_fraction : float
        Held-back tail of each excitation log, in (0, 0.5].
    max_updates : int
        Update attempts allowed (>= 0).
    max_legs : int
        Legs allowed (>= 1).
    goal_tolerance_m : float
        Distance to the goal that counts as arrived (m, > 0).
    seed : int
        Seeds the drives and excitations (>= 0).
    in_run_update : bool
        Also try the serving model updated in-run on the excitation data
        (:meth:`energy.CurrentModel.adapt`) and propose it instead of the refitted model when
        it validates better (the update is then recorded with kind ``"in_run"``).
    update_source : {"manoeuvre", "driven"}
        What a new model is fitted on first (:data:`UPDATE_SOURCES`).
    min_driven_s : float
        Driven data in an update's scope needed to fit on it (s, > 2); less asks for a manoeuvre.
    history_s : float
        Driven data the navigator keeps for updates (s, >= ``min_driven_s``): the memory
        bound over hours of driving.
    interval_level : float
        Coverage of the remaining-energy forecast's central interval, in (0, 1).
    risk : float or None
        Upper quantile of the remaining energy that budget decisions use, in (0.5, 1); None:
        the point forecast.
    forecast_dt_s : float
        Time step (s, > 0) of the stop-turn-go profiles the remaining legs are priced on (0.05 s:
        the example mission's forecasts as at 0.01 s within 0.1 %, five times fewer samples to price).
    forecast_prior_legs, forecast_prior_spread : float
        Weight (legs, > 0) and relative spread (> 0) of the forecast's prior before this run
        has shown anything (:mod:`planner.missions.remaining`).
    forecast_unseen_spread : float
        Relative spread (>= 0) of the energy of the rest on a ground class the robot has not
        driven yet in this run (default 0.4: a model on a ground it never saw is off by 37-55 %
        in the real logs' few-shot protocol); 0 for models already trained on every ground.
    """

    speed_mps: float = 0.5
    leg_length_m: float = 10.0
    policy: UpdatePolicy = field(default_factory=lambda: UpdatePolicy(threshold_pct=10.0, min_samples=50,
                                                                      hysteresis_pct=3.0, min_region_cells=8))
    update_scope: str = "ground_class"
    planner: str = "lattice"
    planner_time_limit_s: float = 1.0
    excitation_duration_s: float = 20.0
    turn_excitation_duration_s: float = 8.0
    excitation_speeds_mps: tuple[float, ...] = (0.2, 0.35, 0.5, 0.65, 0.8)
    excitation_omega_radps: float = 0.5
    validation_fraction: float = 0.25
    max_updates: int = 5
    max_legs: int = 500
    goal_tolerance_m: float = 0.5
    seed: int = 0
    in_run_update: bool = False
    update_source: str = "manoeuvre"
    min_driven_s: float = 20.0
    history_s: float = 600.0
    interval_level: float = 0.8
    risk: float | None = None
    forecast_dt_s: float = 0.05
    forecast_prior_legs: float = 2.0
    forecast_prior_spread: float = 0.1
    forecast_unseen_spread: float = 0.4

    def __post_init__(self) -> None:
        own = "AdaptiveSettings"
        if self.update_source not in UPDATE_SOURCES:
            raise InvalidParameterError(
                f"{own}.update_source must be one of {list(UPDATE_SOURCES)!r}, got {self.update_source!r}")
        check_real("min_driven_s", self.min_driven_s, low=2.0, low_inclusive=False, owner=own)
        check_real("history_s", self.history_s, low=self.min_driven_s, owner=own)
        check_real("interval_level", self.interval_level, low=0.0, low_inclusive=False, high=1.0,
                   high_inclusive=False, owner=own)
        if self.risk is not None:
            check_real("risk", self.risk, low=0.5, high=1.0, high_inclusive=False, owner=own)
        check_real("forecast_dt_s", self.forecast_dt_s, low=0.0, low_inclusive=False, owner=own)
        check_real("forecast_prior_legs", self.forecast_prior_legs, low=0.0, low_inclusive=False, owner=own)
        check_real("forecast_prior_spread", self.forecast_prior_spread, low=0.0, low_inclusive=False, owner=own)
        check_real("forecast_unseen_spread", self.forecast_unseen_spread, low=0.0, owner=own)
        for name in ("speed_mps", "leg_length_m", "planner_time_limit_s", "excitation_omega_radps", "goal_tolerance_m"):
            check_real(name, getattr(self, name), low=0.0, low_inclusive=False, owner=own)
        for name in ("excitation_duration_s", "turn_excitation_duration_s"):
            check_real(name, getattr(self, name), low=2.0, low_inclusive=False, owner=own)
        if not isinstance(self.policy, UpdatePolicy):
            raise InvalidParameterError(f"{own}.policy must be an UpdatePolicy, got {self.policy!r}")
        if self.update_scope not in UPDATE_SCOPES:
            raise InvalidParameterError(f"{own}.update_scope must be one of {list(UPDATE_SCOPES)!r}, got {self.update_scope!r}")
        check_real("validation_fraction", self.validation_fraction, low=0.0, low_inclusive=False, high=0.5, owner=own)
        try:
            speeds = tuple(self.excitation_speeds_mps)
        except TypeError:
            raise InvalidParameterError(
                f"{own}.excitation_speeds_mps must be numbers > 0, got {self.excitation_speeds_mps!r}") from None
        if not speeds:
            raise InvalidParameterError(f"{own}.excitation_speeds_mps must be numbers > 0, got {self.excitation_speeds_mps!r}")
        speeds = tuple(check_real("excitation_speeds_mps", s, low=0.0, low_inclusive=False, owner=own) for s in speeds)
        object.__setattr__(self, "excitation_speeds_mps", speeds)
        check_int("max_updates", self.max_updates, low=0, owner=own)
        check_bool(f"{own}.in_run_update", self.in_run_update)
        check_int("max_legs", self.max_legs, low=1, owner=own)
        seed = check_seed(self.seed, f"{own}.seed")
        if seed is None:
            raise InvalidParameterError(f"{own}.seed must be an integer in [0, 2**32), got None")


def _pair(name: str, value: Any) -> tuple[float, float] | None:
    if value is None:
        return None
    arr = real_array(name, value, ndim=1)
    if arr.shape != (2,):
        raise InvalidParameterError(f"{name} must be a pair of numbers, got {value!r}", parameter=name)
    return float(arr[0]), float(arr[1])


@dataclass(frozen=True, kw_only=True)
class MissionGoal:
    """Where a mission goes, and where it returns when the rest does not fit.

    Parameters
    ----------
    xy_m : (float, float), optional
        The goal in map metres; or ``lonlat_deg`` (exactly one).
    lonlat_deg : (float, float), optional
        The goal in WGS 84 degrees (through the map's CRS).
    depot_xy_m : (float, float), optional
        Where to return when the rest of the mission does not fit (default: no return, stop).

    Raises
    ------
    InvalidParameterError
        Both or neither of ``xy_m`` and ``lonlat_deg``; a point that is not a pair of numbers.

    Examples
    --------
    >>> MissionGoal(xy_m=(40, 70), depot_xy_m=(5, 5)).xy_m
    (40.0, 70.0)
    """

    xy_m: tuple[float, float] | None = None
    lonlat_deg: tuple[float, float] | None = None
    depot_xy_m: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if (self.xy_m is None) == (self.lonlat_deg is None):
            raise InvalidParameterError("give the goal as xy_m or as lonlat_deg (exactly one)",
                                        parameter=("goal_xy_m", "goal_lonlat_deg"))
        object.__setattr__(self, "xy_m", _pair("goal_xy_m", self.xy_m))
        object.__setattr__(self, "lonlat_deg", _pair("goal_lonlat_deg", self.lonlat_deg))
        object.__setattr__(self, "depot_xy_m", _pair("depot_xy_m", self.depot_xy_m))


@dataclass(frozen=True, kw_only=True)
class NavigatorModels:
    """How a navigator prices its edges and fits new models.

    Parameters
    ----------
    physics_ground : GroundParams or str
        Ground (or its preset name) of the physics slope term of the learned edge costs
        (default the asphalt preset); held as ``GroundParams``.
    model_factory : callable, optional
        Returns a new unfitted current model (``fit(logs)`` / ``predict(log)``); default
        :class:`energy.LinearCurrentModel`.
    learned : LearnedEnergyModel, optional
        An edge-cost adapter over the navigator's registry (to reuse its table cache, or a saved
        model's recorded vibration); built when None, with ``physics_ground``.

    Raises
    ------
    InvalidParameterError, UnknownNameError
        Not a ground, a callable or a LearnedEnergyModel; a ground name without a preset.

    Examples
    --------
    >>> NavigatorModels(physics_ground="sand").physics_ground.name
    'sand'
    """

    physics_ground: GroundParams | str = "asphalt"
    model_factory: Callable[[], Any] | None = None
    learned: LearnedEnergyModel | None = None

    def __post_init__(self) -> None:
        ground = self.physics_ground
        if isinstance(ground, str):
            if ground not in GROUND_PRESETS:
                raise UnknownNameError(f"physics_ground {ground!r} has no preset; known grounds: "
                                       f"{sorted(GROUND_PRESETS)!r}", parameter="physics_ground")
            object.__setattr__(self, "physics_ground", ground_preset(ground))
        check_instance("physics_ground", self.physics_ground, GroundParams)
        if self.model_factory is not None and not callable(self.model_factory):
            raise InvalidParameterError(f"model_factory must be callable, got {self.model_factory!r:.80}",
                                        parameter="model_factory")
        if self.learned is not None:
            check_instance("learned", self.learned, LearnedEnergyModel)


@dataclass(frozen=True, kw_only=True)
class ReplayFeed:
    """How a recording is fed to a navigator, where its state is kept and who hears its decisions.

    Parameters
    ----------
    mode : {"auto", "legs", "drive"}
        ``"legs"``: each drive log is a leg, with a checkpoint at its end; ``"drive"``: the
        logs are cut in chunks of ``chunk_s``; ``"auto"``: legs when there are several logs.
    chunk_s : float
        Chunk length (s, > 0) in ``"drive"`` mode.
    speed_up : float, optional
        Pace the replay at this many times real time (> 0; None: as fast as possible).
    state_path : path, optional
        Save the navigator's state here every ``save_every`` checkpoints (a replay that finds a
        state there resumes from it).
    save_every : int
        Checkpoints between saves (>= 1).
    on_decision : callable, optional
        Called with each decision that is not ``"continue"`` (e.g. to print it).

    Raises
    ------
    InvalidParameterError, UnknownNameError
        A bad chunk length, pace, save interval or callback; an unknown mode.

    Examples
    --------
    >>> ReplayFeed(mode="drive", chunk_s=0.5).chunk_s
    0.5
    """

    mode: str = "auto"
    chunk_s: float = 1.0
    speed_up: float | None = None
    state_path: str | os.PathLike[str] | None = None
    save_every: int = 1
    on_decision: Callable[[Any], None] | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        check_choice("mode", self.mode, REPLAY_MODES)
        set_(self, "chunk_s", check_real("chunk_s", self.chunk_s, low=0.0, low_inclusive=False))
        if self.speed_up is not None:
            set_(self, "speed_up", check_real("speed_up", self.speed_up, low=0.0, low_inclusive=False))
        set_(self, "state_path", None if self.state_path is None else Path(self.state_path))
        set_(self, "save_every", check_int("save_every", self.save_every, low=1))
        if self.on_decision is not None and not callable(self.on_decision):
            raise InvalidParameterError(f"on_decision must be callable, got {self.on_decision!r:.80}",
                                        parameter="on_decision")

    @property
    def resumes(self) -> bool:
        """Whether ``state_path`` holds a saved navigator to resume from."""
        return self.state_path is not None and (Path(self.state_path) / "navigator.json").is_file()
