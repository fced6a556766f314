"""Route results: waypoints with their energy (J, Wh), charge (mAh), length, duration and planning facts."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import readonly, real_array
from terrawatt_base.errors import InvalidParameterError, PlanningError

from .edge_cost import EnergyCost
from .points import as_points
from .route_geojson import routes_geojson
from .route_time import route_duration_s

__all__ = ["Route", "RouteComparison", "ROUTE_STATUSES", "evaluate_route", "empty_route"]

#: Planning outcomes. ``exact``: the route reaches the goal. ``approximate``: the planner ran
#: out of budget and returns its route to the state closest to the goal (it does not end at
#: the goal). ``timeout``: no route at all within the budget. ``infeasible``: no valid route
#: exists (start and goal lie in different free regions).
ROUTE_STATUSES = ("exact", "approximate", "timeout", "infeasible")

_NAN = math.nan


def _readonly(arr: Any, shape_tail: tuple[int, ...], name: str) -> np.ndarray:
    """A read-only float copy of ``arr`` of shape ``(K,) + shape_tail`` (NaN allowed: checked later)."""
    a = real_array(name, arr, finite=False)
    if a.ndim != 1 + len(shape_tail) or a.shape[1:] != shape_tail:
        expected = "(K, 2)" if shape_tail else "(K,)"
        raise InvalidParameterError(f"{name} must have shape {expected}, got {a.shape!r}")
    return readonly(a)


@dataclass(frozen=True)
class RouteComparison:
    """The baselines of one route query, computed once per query and only when asked.

    Attributes
    ----------
    shortest : Route
        The shortest-distance route between the same points, evaluated
        (:func:`planner.planning.shortest_route`; status ``"infeasible"`` when there is none).
    lattice_optimum_j : float
        Energy (J), drive and turns, of the minimum-energy route on the 1-cell heading lattice
        (:mod:`planner.heading_lattice`: the 16-connected lattice searched over node and heading,
        the reference optimum of the price every route reports); NaN when that lattice joins no
        route.

    Raises
    ------
    InvalidParameterError
        ``shortest`` not a Route, or a negative / infinite optimum.
    """

    shortest: Route
    lattice_optimum_j: float

    def __post_init__(self) -> None:
        if not isinstance(self.shortest, Route):
            raise InvalidParameterError(f"shortest must be a Route, got {type(self.shortest).__name__!r}")
        value = float(self.lattice_optimum_j)
        if not (math.isnan(value) or (math.isfinite(value) and value >= 0)):
            raise InvalidParameterError(f"lattice_optimum_j must be a finite energy >= 0 or NaN, got {value!r}")
        object.__setattr__(self, "lattice_optimum_j", value)

    @property
    def shortest_energy_j(self) -> float:
        """Energy (J, turns included) of :attr:`shortest`; NaN when it was not found."""
        return self.shortest.energy_j if self.shortest.status == "exact" else _NAN


@dataclass(frozen=True)
class Route:
    """A planned (or evaluated) route and what driving it costs.

    Energies are battery-side, at the planning speed of the :class:`EnergyCost` that
    produced them. Drive energy is the sum of the straight segments; the total adds the
    turns in place at the waypoints.

    Derived (properties): ``found``, ``drive_energy_j``, ``energy_wh``, ``charge_mah``,
    ``shortest_energy_j``, ``lattice_energy_j``, ``energy_saved_pct``, ``optimality_ratio``.

    Attributes
    ----------
    status : str
        One of :data:`ROUTE_STATUSES`.
    waypoints_m : ndarray, shape (K, 2)
        Route vertices (m), start first; empty ``(0, 2)`` when no route was found.
    segment_energy_j : ndarray, shape (K - 1,)
        Energy of each straight segment (J).
    turn_energy_j : ndarray, shape (K,)
        Energy of stopping, turning in place and starting again at each waypoint (J; 0 where
        the robot drives through); at both ends half a stop-and-go each, the start from rest
        and the stop at rest (:meth:`planner.EnergyCost.turn_energies_j`).
    length_m : float
        Horizontal (map) length of the route (m); NaN when no route was found (likewise
        for the other totals).
    duration_s : float
        The time the robot takes to drive it stop-turn-go from rest to rest at the planning
        speed and turn rate, its ramps included (s; :func:`planner.route_time.route_duration_s`).
    energy_j : float
        Total energy: segments plus turns (J).
    battery_voltage_v : float
        Battery voltage used for the charge in mAh (V).
    planner : str
        Name of the planner that produced the route.
    planning_time_s : float
        Wall-clock planning time (s), map preparation (tables, lattice graph, numba
        compilation) excluded.
    comparison : RouteComparison or None
        The baselines of the same query (``plan_route(..., compare=True)``); None when not
        computed.

    Raises
    ------
    InvalidParameterError
        Unknown status, inconsistent shapes, negative or non-finite values on a found route.
    """

    status: str
    waypoints_m: np.ndarray
    segment_energy_j: np.ndarray
    turn_energy_j: np.ndarray
    length_m: float
    duration_s: float
    energy_j: float
    battery_voltage_v: float
    planner: str
    planning_time_s: float
    comparison: RouteComparison | None = None

    def __post_init__(self) -> None:
        if self.status not in ROUTE_STATUSES:
            raise InvalidParameterError(f"status must be one of {ROUTE_STATUSES!r}, got {self.status!r}")
        wp = _readonly(self.waypoints_m, (2,), "waypoints_m")
        seg = _readonly(self.segment_energy_j, (), "segment_energy_j")
        turn = _readonly(self.turn_energy_j, (), "turn_energy_j")
        object.__setattr__(self, "waypoints_m", wp)
        object.__setattr__(self, "segment_energy_j", seg)
        object.__setattr__(self, "turn_energy_j", turn)
        k = wp.shape[0]
        if self.found:
            if k < 2:
                raise InvalidParameterError(f"a route with status {self.status!r} needs >= 2 waypoints, got {k}")
            if seg.shape != (k - 1,) or turn.shape != (k,):
                raise InvalidParameterError(
                    f"{k} waypoints need {k - 1} segment energies and {k} turn energies, got "
                    f"{seg.shape[0]} and {turn.shape[0]}"
                )
            if not (np.all(np.isfinite(wp)) and np.all(np.isfinite(seg)) and np.all(np.isfinite(turn))):
                raise InvalidParameterError(
                    "a found route needs finite waypoints and energies (does a segment cross a blocked cell?)"
                )
            for name in ("length_m", "duration_s", "energy_j"):
                v = getattr(self, name)
                if not (math.isfinite(v) and v >= 0):
                    raise InvalidParameterError(f"{name} must be finite and >= 0 on a found route, got {v!r}")
        elif k != 0 or seg.size or turn.size:
            raise InvalidParameterError(f"a route with status {self.status!r} has no waypoints, got {k}")
        for name in ("battery_voltage_v",):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise InvalidParameterError(f"{name} must be finite and > 0, got {v!r}")
        if not (math.isfinite(self.planning_time_s) and self.planning_time_s >= 0):
            raise InvalidParameterError(f"planning_time_s must be finite and >= 0, got {self.planning_time_s!r}")
        if not isinstance(self.planner, str) or not self.planner:
            raise InvalidParameterError(f"planner must be a non-empty name, got {self.planner!r}")
        if self.comparison is not None and not isinstance(self.comparison, RouteComparison):
            raise InvalidParameterError(
                f"comparison must be a RouteComparison or None, got {type(self.comparison).__name__!r}"
            )

    # ------------------------------------------------------------------ derived
    @property
    def found(self) -> bool:
        """True for ``exact`` and ``approximate`` routes (they have waypoints)."""
        return self.status in ("exact", "approximate")

    @property
    def drive_energy_j(self) -> float:
        """Sum of the segment energies (J), without turns (the OMPL planners' objective; the lattice planner
        and the refinement minimise :attr:`energy_j`, turns included)."""
        return float(self.segment_energy_j.sum()) if self.found else _NAN

    @property
    def energy_wh(self) -> float:
        """Total energy in watt-hours."""
        return self.energy_j / 3600.0

    @property
    def charge_mah(self) -> float:
        """Battery charge (mAh) at :attr:`battery_voltage_v`: ``J / V / 3.6``."""
        return self.energy_j / self.battery_voltage_v / 3.6

    @property
    def shortest_energy_j(self) -> float:
        """Energy (J, with turns) of the shortest-distance route between the same points (the
        straight line when it is free, else the shortest lattice route straightened by
        line-of-sight shortcuts); NaN when not compared or when there is none."""
        return _NAN if self.comparison is None else self.comparison.shortest_energy_j

    @property
    def lattice_energy_j(self) -> float:
        """Energy (J), drive and turns, of the minimum-energy route on the 1-cell heading lattice
        (the reference optimum); NaN when not compared or when there is none."""
        return _NAN if self.comparison is None else self.comparison.lattice_optimum_j

    @property
    def energy_saved_pct(self) -> float:
        """Energy saved against the shortest-distance route, in percent (negative: it costs more).

        NaN unless the route reaches the goal (``exact``): a route that stops short would
        look cheaper than one that arrives."""
        if not (self.status == "exact" and math.isfinite(self.shortest_energy_j) and self.shortest_energy_j > 0):
            return _NAN
        return 100.0 * (self.shortest_energy_j - self.energy_j) / self.shortest_energy_j

    @property
    def optimality_ratio(self) -> float:
        """Energy (drive and turns) divided by the heading lattice's optimum of the same price (< 1:
        better than any 16-connected lattice route); NaN unless the route reaches the goal (``exact``)."""
        if not (self.status == "exact" and math.isfinite(self.lattice_energy_j) and self.lattice_energy_j > 0):
            return _NAN
        return self.energy_j / self.lattice_energy_j

    def raise_for_status(self) -> Route:
        """Return ``self`` if the route reaches the goal (``exact``), else raise.

        Raises
        ------
        PlanningError
            For ``approximate``, ``timeout`` and ``infeasible`` routes.
        """
        if self.status != "exact":
            raise PlanningError(
                f"planner {self.planner!r} returned status {self.status!r} after {self.planning_time_s:.3f} s; "
                "expected an exact route"
            )
        return self

    def to_geojson(self, where: Any, *, crs: str | None = None, name: str = "route") -> dict[str, Any]:
        """This route as a GeoJSON FeatureCollection of one LineString (:func:`planner.route_geojson.routes_geojson`:
        WGS 84 when ``where``, the map or its Grid, has a CRS; per-vertex cumulative energy)."""
        return routes_geojson({name: self}, where, crs=crs)

    def replace(self, **changes: Any) -> Route:
        """A copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    def summary(self) -> dict[str, Any]:
        """Scalars of the route as a flat dict of JSON-friendly values (units in the keys)."""
        return {
            "status": self.status,
            "planner": self.planner,
            "n_waypoints": int(self.waypoints_m.shape[0]),
            "length_m": self.length_m,
            "duration_s": self.duration_s,
            "drive_energy_j": self.drive_energy_j,
            "energy_j": self.energy_j,
            "energy_wh": self.energy_wh,
            "charge_mah": self.charge_mah,
            "battery_voltage_v": self.battery_voltage_v,
            "planning_time_s": self.planning_time_s,
            "shortest_energy_j": self.shortest_energy_j,
            "energy_saved_pct": self.energy_saved_pct,
            "lattice_energy_j": self.lattice_energy_j,
            "optimality_ratio": self.optimality_ratio,
        }

    def __repr__(self) -> str:
        if not self.found:
            return (
                f"Route(status={self.status!r}, planner={self.planner!r}, "
                f"planning_time_s={self.planning_time_s:.3f})"
            )
        return (
            f"Route(status={self.status!r}, planner={self.planner!r}, waypoints={self.waypoints_m.shape[0]}, "
            f"length_m={self.length_m:.2f}, energy_j={self.energy_j:.1f}, charge_mah={self.charge_mah:.1f}, "
            f"duration_s={self.duration_s:.1f}, planning_time_s={self.planning_time_s:.3f})"
        )


def evaluate_route(
    cost: EnergyCost,
    waypoints_m: Any,
    *,
    status: str = "exact",
    planner: str = "evaluated",
    planning_time_s: float = 0.0,
) -> Route:
    """Cost a polyline: per-segment and per-turn energies, length, duration, totals.

    Parameters
    ----------
    cost : EnergyCost
        Edge costs of the map (speed, turn rate and battery voltage come from it).
    waypoints_m : array_like, shape (K, 2), K >= 2
        Route vertices (m).
    status, planner, planning_time_s
        Stored on the :class:`Route`.

    Returns
    -------
    Route

    Raises
    ------
    InvalidParameterError
        Fewer than 2 waypoints, NaN coordinates, or a segment that crosses a blocked cell.
    OutOfBoundsError
        A waypoint outside the map.

    Examples
    --------
    >>> from planner import CostSpec
    >>> from terrain import flat_map
    >>> tmap = flat_map((30, 40), 1.0)  # level asphalt, 1 m cells
    >>> cost = CostSpec(speed_mps=0.5).build(tmap)  # the Husky's physics on the asphalt preset
    >>> route = evaluate_route(cost, [[0.5, 0.5], [10.5, 0.5], [10.5, 5.5]])
    >>> route.length_m, bool(route.turn_energy_j[1] > 0)
    (15.0, True)
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    pts = as_points(waypoints_m, "waypoints_m")
    if pts.shape[0] < 2:
        raise InvalidParameterError(f"waypoints_m needs at least 2 points, got {pts.shape[0]}")
    seg = cost.segment_energy_j(pts[:-1], pts[1:])
    if not np.all(np.isfinite(seg)):
        i = int(np.flatnonzero(~np.isfinite(seg))[0])
        raise InvalidParameterError(
            f"segment {i} from {tuple(pts[i].tolist())!r} to {tuple(pts[i + 1].tolist())!r} m crosses a "
            "blocked cell (obstacle or steeper than max_slope_rad); expected a valid route"
        )
    _, turns = cost.turn_energies_j(pts)
    lengths = np.hypot(*np.diff(pts, axis=0).T)
    length = float(lengths.sum())
    duration = route_duration_s(pts, cost.speed_mps, cost.turn_rate_radps)
    return Route(
        status=status,
        waypoints_m=pts,
        segment_energy_j=seg,
        turn_energy_j=turns,
        length_m=length,
        duration_s=duration,
        energy_j=float(seg.sum() + turns.sum()),
        battery_voltage_v=cost.battery_voltage_v,
        planner=planner,
        planning_time_s=float(planning_time_s),
    )


def empty_route(status: str, planner: str, planning_time_s: float, battery_voltage_v: float) -> Route:
    """A route without waypoints (``timeout`` or ``infeasible``)."""
    if status in ("exact", "approximate"):
        raise InvalidParameterError(f"an empty route cannot have status {status!r}")
    return Route(
        status=status,
        waypoints_m=np.empty((0, 2)),
        segment_energy_j=np.empty(0),
        turn_energy_j=np.empty(0),
        length_m=_NAN,
        duration_s=_NAN,
        energy_j=_NAN,
        battery_voltage_v=battery_voltage_v,
        planner=planner,
        planning_time_s=planning_time_s,
    )
