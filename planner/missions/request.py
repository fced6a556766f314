"""A mission as asked for: its options checked together once, its start and goal placed on the map (MissionRequest)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from energy import GROUND_PRESETS
from terrain import TerrainMap
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M
from terrawatt_base.checks import check_bool, check_choice, check_int
from terrawatt_base.dask_client import check_dask_options
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from ..points import point_on_map
from ..tables import check_planning_risk
from .mission_report import check_preset_grounds
from .monte_carlo_model import MC_DRAW_MODES

__all__ = ["MissionRequest", "MISSION_OPTIONS"]

#: The options :class:`MissionRequest` names in its messages (and its errors carry,
#: :attr:`~terrawatt_base.errors.TerrawattError.parameter`).
MISSION_OPTIONS = ("start", "start_lonlat", "goal", "goal_lonlat", "prior_ground", "monte_carlo", "workers",
                   "scheduler", "model", "risk", "draw_from")


@dataclass(frozen=True)
class MissionRequest:
    """A mission or a Monte Carlo study of one, as asked for: checked when made, before any work.

    :func:`planner.missions.mission_report.simulate_adaptive_mission` drives one adaptive
    mission, :func:`planner.missions.monte_carlo_report.monte_carlo_mission` a study of
    ``monte_carlo`` missions; the request checks the options that go together for either, and
    :meth:`points` places its start and goal on the map (the bundled example's by default).

    Attributes
    ----------
    on_example : bool
        Whether the map is the bundled example map (start and goal then default to its own);
        on another map, start and goal are required.
    start, start_lonlat, goal, goal_lonlat : (float, float) or None
        Start and goal in the map's metres or in WGS 84 degrees, at most one form each.
    prior_ground : str
        Ground preset of the prior model.
    monte_carlo : int or None
        Missions of a Monte Carlo study (>= 1); None: one adaptive mission.
    workers, scheduler
        Where the study runs (:func:`terrawatt_base.dask_client.check_dask_options`); a study only.
    model : object or None
        A saved current model (or its file; only whether it is given counts).
    risk : float or None
        A study's risk level in (0, 1).
    draw_from : {"parameters", "model"}
        What a study draws; ``"model"`` needs ``model``.

    Raises
    ------
    InvalidParameterError
        Options that do not go together; a bad number.
    UnknownNameError
        ``prior_ground`` without a preset; ``draw_from`` not a draw mode.

    Examples
    --------
    >>> from terrain.procedural import example_map
    >>> MissionRequest().points(example_map())
    ((10.0, 10.0), (150.0, 150.0))
    >>> MissionRequest(risk=0.9)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    terrawatt_base.errors.InvalidParameterError: risk Q of mission checks the route's Q quantile ... study; ...
    """

    on_example: bool = True
    start: Any = None
    start_lonlat: Any = None
    goal: Any = None
    goal_lonlat: Any = None
    prior_ground: str = "asphalt"
    monte_carlo: int | None = None
    workers: int = 1
    scheduler: str | None = None
    model: Any = None
    risk: float | None = None
    draw_from: str = "parameters"

    def __post_init__(self) -> None:
        check_bool("on_example", self.on_example)
        if self.prior_ground not in GROUND_PRESETS:
            raise UnknownNameError(f"prior_ground {self.prior_ground!r} has no preset; known grounds: "
                                   f"{sorted(GROUND_PRESETS)!r}", parameter="prior_ground")
        if self.monte_carlo is None and (self.workers != 1 or self.scheduler is not None):
            raise InvalidParameterError("workers and scheduler apply to monte_carlo N only",
                                        parameter=("workers", "scheduler", "monte_carlo"))
        if self.monte_carlo is not None:
            check_int("monte_carlo", self.monte_carlo, low=1)
        check_dask_options(self.workers, self.scheduler)
        if self.risk is not None:
            check_planning_risk(self.risk, "risk")
            if self.monte_carlo is None:
                raise InvalidParameterError(
                    "risk Q of mission checks the route's Q quantile against the usable battery in a monte_carlo N "
                    "study; the adaptive mission does not take it yet", parameter=("risk", "monte_carlo"))
        if check_choice("draw_from", self.draw_from, MC_DRAW_MODES) == "model" and self.model is None:
            raise InvalidParameterError("`draw_from` model draws from a saved model's predictive distribution: give "
                                        "`model` FILE", parameter=("draw_from", "model"))
        if not self.on_example and (
                (self.start is None and self.start_lonlat is None) or (self.goal is None and self.goal_lonlat is None)):
            raise InvalidParameterError("start and goal (or start_lonlat and goal_lonlat) are required with a map file",
                                        parameter=("start", "goal", "start_lonlat", "goal_lonlat"))

    def points(self, terrain: TerrainMap) -> tuple[tuple[float, float], tuple[float, float]]:
        """Start and goal in ``terrain``'s metres (:func:`planner.points.point_on_map`; the example's when not given),
        once every ground of ``terrain`` is known to have a preset (the truth simulator drives presets).

        Raises
        ------
        InvalidParameterError
            A point not two finite coordinates, given in both forms, or in degrees on a map without CRS.
        OutOfBoundsError
            Degrees off the map.
        UnknownNameError
            A ground of the map without a preset (:func:`planner.missions.mission_report.check_preset_grounds`).
        """
        start = point_on_map(self.start, self.start_lonlat, terrain, names=("start", "start_lonlat"))
        goal = point_on_map(self.goal, self.goal_lonlat, terrain, names=("goal", "goal_lonlat"))
        check_preset_grounds(terrain)
        return start or EXAMPLE_START_XY_M, goal or EXAMPLE_GOAL_XY_M
