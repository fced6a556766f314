"""How a tour is searched for (:class:`TourSearch`) and the alike robots of a tour on a map (:class:`TourFleet`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from energy import Battery
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

from ..tables import check_planning_risk

__all__ = ["TOUR_SOLVERS", "TourSearch", "TourFleet"]

#: The routing solvers a tour is solved by (``None``: PyVRP, or OR-Tools with charging points).
TOUR_SOLVERS = ("pyvrp", "ortools")


@dataclass(frozen=True, kw_only=True)
class TourSearch:
    """How the tour problem is solved: the risk level every tour must hold at, the solver, its time and its seed.

    Parameters
    ----------
    risk : float
        The quantile Q (in [0.5, 1)) of each tour's energy that must come back above its reserve.
    time_limit_s : float
        The routing solver's time budget (s, > 0).
    seed : int
        The routing solver's seed (``None`` is 0).
    solver : {"pyvrp", "ortools"}, optional
        The routing solver; default PyVRP, or OR-Tools with charging points.
    improve : bool
        Whether the solver's tours go through the improvement step priced as driven
        (:func:`planner.tours.improve_tours`; default True; False: the solver's tours as they are, to compare).

    Raises
    ------
    InvalidParameterError, UnknownNameError
        A risk outside [0.5, 1), a bad time limit or seed; an unknown solver.

    Examples
    --------
    >>> TourSearch(risk=0.95, time_limit_s=2.0).seed
    0
    """

    risk: float = 0.9
    time_limit_s: float = 10.0
    seed: int | None = 0
    solver: str | None = None
    improve: bool = True

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "risk", check_planning_risk(self.risk, "risk"))
        set_(self, "time_limit_s", check_real("time_limit_s", self.time_limit_s, low=0.0, low_inclusive=False))
        set_(self, "seed", check_seed(self.seed) or 0)
        if self.solver is not None:
            check_choice("solver", self.solver, TOUR_SOLVERS)
        set_(self, "improve", check_bool("improve", self.improve))


@dataclass(frozen=True, kw_only=True)
class TourFleet:
    """Alike robots of a tour on a map: one battery each, one shared depot or one each, the longest tour.

    Parameters
    ----------
    battery : Battery
        What every robot carries (e.g. :func:`planner.missions.mission_report.mission_battery`: a
        capacity at the robot's voltage with its reserve).
    depot_xy_m : (float, float) or sequence of (float, float)
        One depot for all, or one per robot (m); held as one per robot.
    n_robots : int
        Robots (>= 1).
    max_duration_s : float, optional
        The longest a tour may last (s, > 0; ``None``: no limit).

    Raises
    ------
    InvalidParameterError
        Not a Battery; fewer than one robot; several depots but not one per robot; a bad duration.

    Examples
    --------
    >>> from energy import Battery
    >>> TourFleet(battery=Battery(0.2, 24.0), depot_xy_m=(1, 1), n_robots=2).depot_xy_m
    ((1.0, 1.0), (1.0, 1.0))
    """

    battery: Battery
    depot_xy_m: tuple[float, float] | Sequence[tuple[float, float]]
    n_robots: int = 1
    max_duration_s: float | None = None

    def __post_init__(self) -> None:
        check_instance("battery", self.battery, Battery)
        n = check_int("n_robots", self.n_robots, low=1)
        try:
            depots = np.asarray(self.depot_xy_m, dtype=float)
        except (TypeError, ValueError):
            raise InvalidParameterError(f"depot_xy_m must be one point or one per robot, got {self.depot_xy_m!r:.80}",
                                        parameter="depot_xy_m") from None
        depots = depots.reshape(-1, 2) if depots.ndim == 2 else np.tile(depots, (n, 1))
        if depots.shape[0] != n:
            raise InvalidParameterError(f"depot_xy_m must be one point or one per robot (n_robots={n}), got "
                                        f"{depots.shape[0]} points", parameter="depot_xy_m")
        object.__setattr__(self, "depot_xy_m", tuple((float(x), float(y)) for x, y in depots))
        check_optional_real("max_duration_s", self.max_duration_s, low=0.0, low_inclusive=False)
