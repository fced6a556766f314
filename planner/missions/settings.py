"""Knobs of the adaptive mission loop: :class:`AdaptiveSettings` and the update scopes."""

from __future__ import annotations

from dataclasses import dataclass, field

from terrain import InvalidParameterError
from terrawatt_base.checks import check_bool, check_int, check_real, check_seed

from ..registry import UpdatePolicy

__all__ = ["UPDATE_SCOPES", "UPDATE_SOURCES", "AdaptiveSettings"]

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
