"""A mission as asked for: its options checked together once, its start and goal placed on the map (MissionRequest)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from energy import GROUND_PRESETS
from terrain import TerrainMap
from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M
from terrawatt_base.checks import check_bool, check_choice, check_int, option_names
from terrawatt_base.dask_client import check_dask_options
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from ..points import point_on_map
from ..risk import check_planning_risk
from .mission_report import check_preset_grounds
from .monte_carlo_model import MC_DRAW_MODES

__all__ = ["MissionRequest", "MISSION_OPTIONS"]

#: The options :class:`MissionRequest` names in its messages (``names`` keys).
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
    names : mapping of str to str or None
        How messages name the options of :data:`MISSION_OPTIONS` (the CLI passes its flags); an
        option not in it is named as itself.

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
    names: Mapping[str, str] | None = field(default=None, repr=False, compare=False)

    def _name(self, key: str) -> str:
        return option_names(self.names, MISSION_OPTIONS)[key]

    def __post_init__(self) -> None:
        option_names(self.names, MISSION_OPTIONS)  # a bad mapping is refused when made
        n = self._name
        check_bool("on_example", self.on_example)
        if self.prior_ground not in GROUND_PRESETS:
            raise UnknownNameError(f"{n('prior_ground')} {self.prior_ground!r} has no preset; known grounds: "
                                   f"{sorted(GROUND_PRESETS)!r}")
        if self.monte_carlo is None and (self.workers != 1 or self.scheduler is not None):
            raise InvalidParameterError(f"{n('workers')} and {n('scheduler')} apply to {n('monte_carlo')} N only")
        if self.monte_carlo is not None:
            check_int(n("monte_carlo"), self.monte_carlo, low=1)
        check_dask_options(self.workers, self.scheduler, flags=(n("workers"), n("scheduler")))
        if self.risk is not None:
            check_planning_risk(self.risk, n("risk"))
            if self.monte_carlo is None:
                raise InvalidParameterError(
                    f"{n('risk')} Q of mission checks the route's Q quantile against the usable battery in a "
                    f"{n('monte_carlo')} N study; the adaptive mission does not take it yet")
        if check_choice(n("draw_from"), self.draw_from, MC_DRAW_MODES) == "model" and self.model is None:
            raise InvalidParameterError(f"{n('draw_from')} model draws from a saved model's predictive distribution: "
                                        f"give {n('model')} FILE")
        if not self.on_example and (
                (self.start is None and self.start_lonlat is None) or (self.goal is None and self.goal_lonlat is None)):
            raise InvalidParameterError(f"{n('start')} and {n('goal')} (or {n('start_lonlat')} and "
                                        f"{n('goal_lonlat')}) are required with a map file")

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
        n = self._name
        start = point_on_map(self.start, self.start_lonlat, terrain, names=(n("start"), n("start_lonlat")))
        goal = point_on_map(self.goal, self.goal_lonlat, terrain, names=(n("goal"), n("goal_lonlat")))
        check_preset_grounds(terrain)
        return start or EXAMPLE_START_XY_M, goal or EXAMPLE_GOAL_XY_M
