"""PlanningProblem: one query — the edge costs (map, robot, speed, limits) and two free points — validated once.

Every planner, every comparison and every pricing of a query starts from the same checks:
the points are pairs of finite metres on the map, on free cells (not an obstacle, not ground
steeper than the cost's slope limit) and distinct. A :class:`PlanningProblem` makes them
once; what takes one (:func:`planner.plan_route` inside, the planners of
:data:`planner.planning.PLANNER_SEARCHES`, :func:`planner.compare_route`,
:func:`planner.shortest_route`) trusts it instead of checking again.

The map, the robot, the speed and the limits are those of the cost
(:class:`~planner.EnergyCost`: its terrain, battery voltage and turn rate, planning speed,
slope limit), so a problem is a cost and two points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrawatt_base.checks import fmt_number
from terrawatt_base.errors import BlockedPositionError, InvalidParameterError, OutOfBoundsError

from .edge_cost import EnergyCost

__all__ = ["PlanningProblem", "query_point"]


def query_point(cost: EnergyCost, xy: Any, name: str) -> np.ndarray:
    """``xy`` as a float array ``(x_m, y_m)``, checked to lie on a free cell of ``cost``'s map.

    Raises
    ------
    InvalidParameterError
        Not a pair of finite numbers.
    OutOfBoundsError
        Outside the map.
    BlockedPositionError
        On an obstacle or on ground steeper than ``cost.max_slope_rad``.
    """
    try:
        p = np.asarray(xy, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be (x_m, y_m), got {xy!r}") from None
    if p.shape != (2,):
        raise InvalidParameterError(f"{name} must be (x_m, y_m), got {xy!r}")
    if not np.all(np.isfinite(p)):
        raise InvalidParameterError(f"{name} must be finite coordinates in metres, got {xy!r}")
    if not cost.terrain.contains(p[0], p[1]):
        raise OutOfBoundsError(f"{name} {tuple(p.tolist())!r} m lies outside the map bounds {cost.terrain.bounds!r}")
    r, c = cost.terrain.rowcol(p[0], p[1])
    if cost.blocked[r, c]:
        if cost.terrain.obstacle[r, c]:
            why = "on an obstacle"
        else:
            why = (
                f"on ground steeper ({math.degrees(float(cost.terrain.slope_rad[r, c])):.1f} deg) than "
                f"max_slope_rad ({math.degrees(cost.max_slope_rad):.1f} deg)"
            )
        raise BlockedPositionError(
            f"{name} {tuple(p.tolist())!r} m lies {why} (cell row {r}, col {c}); expected a free cell"
        )
    return p


@dataclass(frozen=True)
class PlanningProblem:
    """A route query: edge costs and a start and a goal, each on a free cell, checked once.

    Parameters
    ----------
    cost : EnergyCost
        The edge costs: the map, the robot (battery voltage, turn rate), the planning speed
        and the slope limit.
    start_xy_m, goal_xy_m : (float, float)
        World coordinates (m) of two different free cells.

    Attributes
    ----------
    start, goal : ndarray, shape (2,)
        The checked points (read-only float arrays).
    connected : bool
        Whether start and goal lie in one 4-connected region of free cells (a route can
        exist; exact when every grade of every ground is drivable).

    Raises
    ------
    InvalidParameterError
        ``cost`` not an EnergyCost; a point not a pair of finite numbers; start equals goal.
    OutOfBoundsError
        A point outside the map.
    BlockedPositionError
        A point on an obstacle or on ground steeper than ``cost.max_slope_rad``.

    Examples
    --------
    >>> from planner import EnergyCost
    >>> from terrain import flat_map
    >>> from planner import CostSpec
    >>> problem = PlanningProblem(CostSpec().build(flat_map((20, 30), 1.0)), (2.5, 2.5), (27.5, 17.5))
    >>> problem.connected, problem.start.tolist()
    (True, [2.5, 2.5])
    """

    cost: EnergyCost
    start_xy_m: tuple[float, float]
    goal_xy_m: tuple[float, float]
    start: np.ndarray = field(init=False, repr=False, compare=False)
    goal: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.cost, EnergyCost):
            raise InvalidParameterError(f"cost must be an EnergyCost, got {type(self.cost).__name__!r}")
        start = query_point(self.cost, self.start_xy_m, "start_xy_m")
        goal = query_point(self.cost, self.goal_xy_m, "goal_xy_m")
        if np.array_equal(start, goal):
            raise InvalidParameterError(
                f"start equals goal ({fmt_number(start[0], 10)}, {fmt_number(start[1], 10)}) m: there is no route to "
                "plan; expected two different points"
            )
        start.setflags(write=False)
        goal.setflags(write=False)
        object.__setattr__(self, "start", start)
        object.__setattr__(self, "goal", goal)
        object.__setattr__(self, "start_xy_m", (float(start[0]), float(start[1])))
        object.__setattr__(self, "goal_xy_m", (float(goal[0]), float(goal[1])))

    @property
    def terrain(self) -> TerrainMap:
        """The map of the cost."""
        return self.cost.terrain

    @property
    def key(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """``(start, goal)`` as plain tuples: the query's key in the cost's result cache."""
        return self.start_xy_m, self.goal_xy_m

    @property
    def connected(self) -> bool:
        labels = self.cost.components()
        rs, cs = self.terrain.rowcol(self.start[0], self.start[1])
        rg, cg = self.terrain.rowcol(self.goal[0], self.goal[1])
        return bool(labels[rs, cs] == labels[rg, cg])
