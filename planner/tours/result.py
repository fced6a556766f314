"""A planned tour: per robot the ordered sites, the legs with their energy intervals, the state of charge and its band."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from energy import Battery
from energy.battery import S_PER_H
from terrain import TerrainMap
from terrawatt_base.answer import write_answer
from terrawatt_base.atomic import save_figure
from terrawatt_base.formats import result_document, write_result_json
from terrawatt_base.plot_target import check_ax, check_plot_target, new_figure

from ..edge_cost import EnergyCost
from ..ros_export import write_route_bag
from ..route import Route, evaluate_route
from ..route_geojson import write_geojson
from ..route_price import INTERVAL_LEVEL, RouteEnergyInterval
from .pricing import PairPrices
from .sites import TourChargers

__all__ = ["TourLeg", "RobotTour", "TourResult", "TOUR_FORMAT_VERSION", "TOUR_STATUSES"]

#: Version of tour.json (format ``terrawatt-tour``); 2: each robot's timeline (service time, arrival, start of
#: service, return) and the sites' time windows; 3: charging points: each robot's ``stops`` in visiting order (sites
#: and charging stops, ``charging_stops`` their indices), its timeline and service per stop, its ``segments`` between
#: charges with their energy at Q and budget, and the ``chargers``.
TOUR_FORMAT_VERSION = 4
#: What a tour query answers: tours were planned, or no site is reachable at Q by any robot.
TOUR_STATUSES = ("planned", "nothing reachable")


@dataclass(frozen=True)
class TourLeg:
    """One leg of a tour: from a place to the next, the planner's route and its energy.

    Attributes
    ----------
    start, end : str
        Names of the depot / sites it joins.
    waypoints_m : ndarray, shape (K, 2)
        The route (m).
    energy : RouteEnergyInterval
        The leg's energy distribution (mean, sd; the drive and turns, not the service): its route and, leaving a
        stop, the turn in place there from the heading the robot arrived on (none leaving the depot), so the legs
        of a tour add up to its energy.
    duration_s : float
        Driving time (s): its route driven stop-turn-go from rest to rest and, leaving a stop, the pivot there
        (:meth:`planner.tours.pricing.PairPrices.turn_time_s`), so the legs of a tour add up to its driving time.
    """

    start: str
    end: str
    waypoints_m: np.ndarray = field(repr=False)
    energy: RouteEnergyInterval
    duration_s: float

    def to_dict(self) -> dict[str, Any]:
        """The leg in tour.json."""
        lo, hi = self.energy.interval_j(INTERVAL_LEVEL)
        return {"from": self.start, "to": self.end, "energy_j": self.energy.mean_j, "sd_j": self.energy.sd_j,
                "interval_j": [lo, hi], "duration_s": self.duration_s,
                "waypoints_m": np.asarray(self.waypoints_m).tolist()}


@dataclass(frozen=True)
class RobotTour:
    """One robot's tour: depot, the sites in order (charging on the way where it stops at chargers), back to the depot.

    Attributes
    ----------
    robot : str
        The robot's name.
    battery : Battery
        Its pack (capacity, voltage, reserve, initial charge).
    depot_xy_m : (float, float)
        Its depot (m).
    sites : tuple of str
        The sites visited, in order.
    legs : tuple of TourLeg
        ``depot -> stops[0] -> ... -> depot`` (empty when no site is visited).
    service_energy_j : tuple of float
        Energy spent at each stop (J; 0 at a charger).
    value : float
        The sum of the visited sites' values.
    energy : RouteEnergyInterval
        The whole tour's energy as driven (its legs joined, the turn at every stop included, and the service; the
        spreads of one ground add along the tour), charges aside.
    cumulative : tuple of RouteEnergyInterval
        The energy spent by the end of each leg since the depot or the last charge (at each arrival, service
        included).
    budget_j : float
        What the battery may spend above its reserve from its initial charge (J): the first segment's budget.
    risk : float
        The level Q the tour holds at.
    service_time_s : tuple of float
        Time spent at each stop (s): a site's service, a charger's booked stop time.
    arrival_s, service_start_s : tuple of float
        When the robot, leaving its depot at 0, arrives at each stop and when it starts its service
        there (s): later than the arrival when it waits for the site's time window to open.
    return_s : float
        When it is back at its depot (s; driving, waiting and service).
    max_duration_s : float or None
        The robot's longest tour (s), if it has one.
    charging_stops : tuple of int
        Indices into :attr:`stops` of the stops at chargers, where the battery is charged to full.
    waiting_energy_j : tuple of float
        Energy spent waiting at each stop for its window to open (J): the robot's standby power times the
        wait (in :attr:`cumulative` and :attr:`energy` with the service).
    """

    robot: str
    battery: Battery
    depot_xy_m: tuple[float, float]
    sites: tuple[str, ...]
    legs: tuple[TourLeg, ...]
    service_energy_j: tuple[float, ...]
    value: float
    energy: RouteEnergyInterval
    cumulative: tuple[RouteEnergyInterval, ...]
    budget_j: float
    risk: float
    service_time_s: tuple[float, ...] = ()
    arrival_s: tuple[float, ...] = ()
    service_start_s: tuple[float, ...] = ()
    return_s: float = 0.0
    max_duration_s: float | None = None
    charging_stops: tuple[int, ...] = ()
    waiting_energy_j: tuple[float, ...] = ()

    @property
    def stops(self) -> tuple[str, ...]:
        """Every place the tour stops at between leaving its depot and coming back, in order: its sites and chargers."""
        return tuple(leg.end for leg in self.legs[:-1])

    @property
    def full_budget_j(self) -> float:
        """What a full battery may spend above its reserve (J): a segment's budget after a charge."""
        return max(1.0 - self.battery.reserve_soc, 0.0) * self.battery.energy_capacity_j

    @property
    def segments(self) -> tuple[RouteEnergyInterval, ...]:
        """The energy of each segment between charges (from the depot or a charge to the next charge or back)."""
        ends = [*self.charging_stops, len(self.legs) - 1] if self.legs else []
        return tuple(self.cumulative[k] for k in ends)

    @property
    def segment_budgets_j(self) -> tuple[float, ...]:
        """Each segment's budget above the reserve (J): from the initial charge, then from a full one."""
        return tuple(self.budget_j if k == 0 else self.full_budget_j for k in range(len(self.segments)))

    def _segment_start_soc(self) -> np.ndarray:
        """Per leg, the state of charge its segment started at: the initial one, or full after a charge."""
        start = np.full(len(self.legs), self.battery.initial_soc)
        for k in self.charging_stops:
            start[k + 1:] = 1.0
        return start

    @property
    def energy_at_risk_j(self) -> float:
        """The tour's energy at Q (J)."""
        return self.energy.quantile_j(self.risk) if self.legs else 0.0

    @property
    def duration_s(self) -> float:
        """Driving time of the tour (s; service time and waiting not included: :attr:`return_s` counts them)."""
        return float(sum(leg.duration_s for leg in self.legs))

    def soc(self, q: float | None = None) -> np.ndarray:
        """State of charge (fraction) at the depot and at the end of each leg (on arrival, before a charge there): at
        the mean, or at energy quantile ``q`` of its segment (the energy since the depot or the last charge)."""
        spent = np.array([c.mean_j if q is None else c.quantile_j(q) for c in self.cumulative])
        after = self._segment_start_soc() - spent / self.battery.energy_capacity_j
        return np.concatenate([[self.battery.initial_soc], after])

    @property
    def arrival_soc_at_risk(self) -> float:
        """State of charge back at the depot with the tour's energy at Q."""
        return float(self.soc(self.risk)[-1]) if self.legs else self.battery.initial_soc

    def to_dict(self) -> dict[str, Any]:
        """The robot's block in tour.json."""
        lo_q, hi_q = 0.5 - INTERVAL_LEVEL / 2, 0.5 + INTERVAL_LEVEL / 2
        return {
            "robot": self.robot, "depot_xy_m": list(self.depot_xy_m), "sites": list(self.sites),
            "value": self.value, "battery_ah": self.battery.capacity_ah, "voltage_v": self.battery.voltage_v,
            "reserve_pct": self.battery.min_reserve_pct, "budget_j": self.budget_j,
            "energy": self.energy.to_dict(), "energy_at_risk_j": self.energy_at_risk_j,
            "duration_s": self.duration_s, "service_energy_j": list(self.service_energy_j),
            "service_time_s": list(self.service_time_s), "arrival_s": list(self.arrival_s),
            "service_start_s": list(self.service_start_s), "return_s": self.return_s,
            "max_duration_s": self.max_duration_s, "stops": list(self.stops),
            "waiting_energy_j": list(self.waiting_energy_j),
            "charging_stops": list(self.charging_stops),
            "segments": [{"to": ([*self.stops, "depot"])[k], "energy": iv.to_dict(),
                          "energy_at_risk_j": iv.quantile_j(self.risk), "budget_j": b}
                         for k, iv, b in zip([*self.charging_stops, len(self.legs) - 1], self.segments,
                                             self.segment_budgets_j)],
            "legs": [leg.to_dict() for leg in self.legs],
            "soc": {"places": ["depot", *self.stops, "depot"][:len(self.legs) + 1],
                    "mean": self.soc().tolist(), "at_risk": self.soc(self.risk).tolist(),
                    "band_level": INTERVAL_LEVEL, "band_low": self.soc(hi_q).tolist(),
                    "band_high": self.soc(lo_q).tolist()},
            "arrival_soc_at_risk": self.arrival_soc_at_risk,
        }


@dataclass(frozen=True)
class TourResult:
    """Which sites each robot visits, in what order, and what is left when it is back.

    Made by :func:`planner.tours.plan_tour`; :meth:`summary` prints it, :meth:`to_dict` is tour.json,
    :meth:`plot` draws the tours on the map and :meth:`plot_soc` the state of charge, :meth:`write`
    writes them all.

    Attributes
    ----------
    status : str
        One of :data:`TOUR_STATUSES`.
    risk : float
        The level Q every tour holds at (its energy at Q leaves the reserve).
    tours : tuple of RobotTour
        One per robot.
    left_out : dict of str to str
        Sites not visited and why (:data:`planner.tours.tour.REASONS`: no route; too far at Q; outside its
        time window; too long for the robots' max_duration_s; not worth it).
    errors : dict of str to str
        Sites that could not be considered (off the map, on an obstacle): the error rows.
    values : dict of str to float
        Every site's value.
    solver : str
        The routing solver.
    pricing_time_s, solve_time_s : float
        Seconds to price the legs and to choose and order the sites.
    solve_rounds : int
        Solves until every tour held at its own quantile.
    where : str
        Where the legs were priced.
    map_label : str
        How the map is named.
    sites_xy_m : dict of str to (float, float)
        Where each site is (m).
    terrain, cost, prices
        The map, its edge costs and the priced legs (not in the JSON).
    time_windows_s : dict of str to (float, float)
        The sites that have a time window: ``(earliest_s, latest_s)`` from the departure.
    chargers : TourChargers or None
        The charging points the tours could stop at.
    sites_added, sites_swapped, improve_time_s : int, int, float
        What the improvement step priced as driven did to the solver's tours (:mod:`planner.tours.improve`): the
        sites it added (an insertion adds one, a swap none), the sites it swapped in for sites of less value, and
        the seconds it took (beside ``solve_time_s``); all 0 when it did not run (``TourSearch(improve=False)``).
    """

    status: str
    risk: float
    tours: tuple[RobotTour, ...]
    left_out: dict[str, str]
    errors: dict[str, str]
    values: dict[str, float]
    solver: str
    pricing_time_s: float
    solve_time_s: float
    solve_rounds: int = 1
    where: str = "in process"
    map_label: str = "map"
    sites_xy_m: dict[str, tuple[float, float]] = field(default_factory=dict)
    terrain: TerrainMap = field(default=None, repr=False, compare=False)  # type: ignore[assignment]
    cost: EnergyCost = field(default=None, repr=False, compare=False)  # type: ignore[assignment]
    prices: PairPrices | None = field(default=None, repr=False, compare=False)
    time_windows_s: dict[str, tuple[float, float]] = field(default_factory=dict)
    chargers: TourChargers | None = None
    sites_added: int = 0
    sites_swapped: int = 0
    improve_time_s: float = field(default=0.0, compare=False)

    @property
    def value(self) -> float:
        """The value collected by all robots."""
        return float(sum(t.value for t in self.tours))

    @property
    def visited(self) -> tuple[str, ...]:
        """Every visited site."""
        return tuple(s for t in self.tours for s in t.sites)

    def summary(self) -> str:
        """What ``terrawatt tour`` prints: per robot its sites, energy at Q and arrival charge; what was left out."""
        n = len(self.values) + len(self.errors)
        lines = [f"tour on {self.map_label}: {n} sites, {len(self.tours)} robot(s), risk level Q = {self.risk:g}",
                 f"status: {self.status}; value {self.value:g} of {sum(self.values.values()):g} "
                 f"({len(self.visited)} sites visited)"]
        for t in self.tours:
            lo, hi = t.energy.interval_j(INTERVAL_LEVEL)
            if t.charging_stops:
                at_q = ", ".join(f"{iv.quantile_j(self.risk) / S_PER_H:.1f} of {b / S_PER_H:.1f}"
                                 for iv, b in zip(t.segments, t.segment_budgets_j))
                held = f"segments between charges at Q {at_q} Wh above the reserve"
            else:
                held = f"at Q {t.energy_at_risk_j / S_PER_H:.1f} of {t.budget_j / S_PER_H:.1f} Wh above the reserve"
            lines.append(
                f"  {t.robot}: {len(t.sites)} sites, value {t.value:g}; energy {t.energy.mean_j / S_PER_H:.1f} Wh "
                f"(P10-P90 {lo / S_PER_H:.1f}-{hi / S_PER_H:.1f}), {held}; back with "
                f"{100 * t.arrival_soc_at_risk:.1f} % at Q (reserve {t.battery.min_reserve_pct:g} %)")
            if t.sites:
                shown = [f"[charge {n}]" if k in t.charging_stops else n for k, n in enumerate(t.stops)]
                home = t.legs[0].start  # "depot", or "depot <k>" with several
                lines.append(f"    {home} -> " + " -> ".join(shown) + f" -> {home}")
                times = [f"{n} {a:.0f}" + (f" (waits until {b:.0f})" if b > a else "")
                         for n, a, b in zip(t.stops, t.arrival_s, t.service_start_s)]
                limit = f" (at most {t.max_duration_s:g} s)" if t.max_duration_s is not None else ""
                lines.append(f"    arrives (s): {', '.join(times)}; back at {t.return_s:.0f} s{limit}")
        reasons: dict[str, list[str]] = {}
        for name, why in {**self.errors, **self.left_out}.items():
            reasons.setdefault(why.split(":")[0], []).append(name)
        for why, names in reasons.items():
            shown = ", ".join(names[:8]) + (f", ... ({len(names)})" if len(names) > 8 else "")
            lines.append(f"left out, {why}: {shown}")
        lines.append(f"pricing {self.pricing_time_s:.2f} s ({self.where}), solving {self.solve_time_s:.2f} s "
                     f"({self.solver}, {self.solve_rounds} round(s))")
        if self.sites_added or self.sites_swapped:
            lines.append(f"improvement step priced as driven: {self.sites_added} site(s) added, {self.sites_swapped} "
                         f"swapped in, in {self.improve_time_s:.2f} s")
        if self.status == "nothing reachable":
            timed = any(why.startswith(("outside its time window", "too long")) for why in self.left_out.values())
            lines.append("nothing reachable: no site can be visited and left with the reserve at Q"
                         + (" in time" if timed else "") + "; a larger battery, a lower reserve or a lower risk level"
                         + (", wider time windows or a longer max duration" if timed else ""))
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        """tour.json: a ``terrawatt-tour`` result document (``format_version`` :data:`TOUR_FORMAT_VERSION`; 4 adds
        what the improvement step did, ``sites_added``, ``sites_swapped`` and ``improve_time_s``)."""
        return result_document("tour", TOUR_FORMAT_VERSION, {
            "status": self.status, "map": self.map_label, "risk": self.risk, "value": self.value,
            "robots": [t.to_dict() for t in self.tours],
            "left_out": [{"site": k, "reason": v} for k, v in self.left_out.items()],
            "errors": [{"site": k, "error": v} for k, v in self.errors.items()],
            "values": dict(self.values),
            "sites_xy_m": {k: list(v) for k, v in self.sites_xy_m.items()},
            "time_windows_s": {k: list(v) for k, v in self.time_windows_s.items()},
            "chargers": self.chargers.to_dict() if self.chargers is not None else {}, "solver": self.solver,
            "pricing_time_s": self.pricing_time_s,
            "solve_time_s": self.solve_time_s, "solve_rounds": self.solve_rounds, "where": self.where,
            "sites_added": self.sites_added, "sites_swapped": self.sites_swapped, "improve_time_s": self.improve_time_s,
        })

    def leg_routes(self) -> dict[str, Route]:
        """Every leg as a :class:`planner.Route` on the cost, named ``"robot: from -> to"``."""
        return {f"{t.robot}: {leg.start} -> {leg.end}": evaluate_route(self.cost, leg.waypoints_m, planner="tour")
                for t in self.tours for leg in t.legs}

    def tour_route(self, robot: int, legs: slice = slice(None)) -> Route:
        """One robot's whole tour (or the slice ``legs`` of its legs, e.g. a segment between charges) as one
        :class:`planner.Route` (its legs joined)."""
        legs = self.tours[robot].legs[legs]
        pts = np.vstack([legs[0].waypoints_m] + [leg.waypoints_m[1:] for leg in legs[1:]])
        return evaluate_route(self.cost, pts, planner="tour")

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None) -> Path | None:
        """The tours on the map (elevation shaded, obstacles dark, sites by value; left-out sites hollow)."""
        target = check_plot_target(path, ax)
        if ax is None:
            fig, ax = new_figure((7.0, 6.5))
        else:
            check_ax(ax)
        from matplotlib.colors import LightSource

        t = self.terrain
        xmin, ymin, xmax, ymax = t.bounds
        step = max(1, int(np.ceil(max(t.shape) / 800)))
        z = np.asarray(t.elevation_m)[::step, ::step]
        if np.ptp(z) > 0:
            shade = LightSource(azdeg=315, altdeg=45).hillshade(z[::-1], vert_exag=3.0, dx=t.cell_size_m * step,
                                                                 dy=t.cell_size_m * step)
        else:
            shade = np.full(z.shape, 0.8)
        ax.imshow(shade, cmap="gray", extent=(xmin, xmax, ymin, ymax), origin="upper", vmin=0, vmax=1)
        blocked = np.asarray(self.cost.blocked)[::step, ::step] if self.cost is not None else None
        if blocked is not None and blocked.any():
            ax.imshow(np.ma.masked_where(~blocked, blocked.astype(float)), cmap="Greys", vmin=0, vmax=1.2,
                      extent=(xmin, xmax, ymin, ymax), origin="lower", alpha=0.8)
        left = [k for k in self.left_out if k in self.values]
        colours = ["tab:red", "tab:blue", "tab:purple", "tab:orange", "tab:green", "tab:brown"]
        for k, tour in enumerate(self.tours):
            c = colours[k % len(colours)]
            for j, leg in enumerate(tour.legs):
                w = leg.waypoints_m
                ax.plot(w[:, 0], w[:, 1], color=c, lw=1.5, label=f"{tour.robot} ({tour.value:g})" if j == 0 else None)
            ax.plot(*tour.depot_xy_m, marker="s", color=c, ms=9, mec="k")
        xy = self.sites_xy_m
        for names, style in ((self.visited, dict(color="k")), (left, dict(mfc="none", mec="k"))):
            pts = np.array([xy[n] for n in names if n in xy]).reshape(-1, 2)
            ax.plot(pts[:, 0], pts[:, 1], "o", ms=4, ls="none", **style)
        if self.chargers is not None:
            ch = self.chargers.xy_m
            ax.plot(ch[:, 0], ch[:, 1], marker="P", ms=9, ls="none", color="gold", mec="k", label="charger")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        charges = sum(len(t.charging_stops) for t in self.tours)
        ax.set_title(f"tours at Q = {self.risk:g}: value {self.value:g}, {len(self.visited)} sites"
                     + (f", {charges} charging stop(s)" if charges else ""))
        if self.tours and any(t.legs for t in self.tours):
            ax.legend(loc="upper right", fontsize=8)
        return save_figure(ax.figure, target) if target is not None else None

    def plot_soc(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None) -> Path | None:
        """State of charge along each tour (per leg): the mean, the P10-P90 band, the value at Q and the reserve."""
        target = check_plot_target(path, ax)
        if ax is None:
            fig, ax = new_figure((7.0, 4.0))
        else:
            check_ax(ax)
        lo_q, hi_q = 0.5 - INTERVAL_LEVEL / 2, 0.5 + INTERVAL_LEVEL / 2
        for tour in self.tours:
            if not tour.legs:
                continue
            x, rise = _with_charges(tour, None)
            line, = ax.plot(x, 100 * rise, marker=".", label=f"{tour.robot} mean")
            ax.fill_between(x, 100 * _with_charges(tour, hi_q)[1], 100 * _with_charges(tour, lo_q)[1],
                            color=line.get_color(), alpha=0.25)
            ax.plot(x, 100 * _with_charges(tour, self.risk)[1], ls="--", color=line.get_color(),
                    label=f"{tour.robot} at Q")
            ax.axhline(tour.battery.min_reserve_pct, color="k", lw=0.8, ls=":")
        driven = [t for t in self.tours if t.legs]
        if len(driven) == 1:
            places = ["depot", *driven[0].stops, "depot"]
            ax.set_xticks(range(len(places)), places, rotation=45 if len(places) > 8 else 0, fontsize=7)
            ax.set_xlabel("arrival at")
        else:
            ax.set_xlabel("legs driven")
        ax.set_ylabel("state of charge (%)")
        charged = any(t.charging_stops for t in self.tours)
        ax.set_title(f"state of charge along the tours\nband P10-P90; dashed: at Q = {self.risk:g}; dotted: reserve"
                     + ("; it rises where a robot charges" if charged else ""), fontsize=10)
        if any(t.legs for t in self.tours):
            ax.legend(fontsize=8)
        return save_figure(ax.figure, target) if target is not None else None

    def write(self, out_dir: str | os.PathLike[str], *, bag: bool = False, on_figure_error: str = "warn") -> list[Path]:
        """Write tour.json, tour.geojson (every leg), tour.png, tour_soc.png and, with ``bag``, each robot's tour as a
        ROS 2 bag (``tour_<k>.mcap``) into ``out_dir``; return the files written."""
        out = Path(out_dir)
        routes = self.leg_routes() if self.cost is not None else {}
        written = write_answer(out, {"tour.json": lambda p: write_result_json(p, self.to_dict()),
                                     "tour.geojson": lambda p: write_geojson(routes, self.terrain, p) if routes else None},
                               {"tour.png": self.plot, "tour_soc.png": self.plot_soc} if self.terrain is not None else {},
                               on_figure_error=on_figure_error)
        if bag:
            for k, tour in enumerate(self.tours):
                if tour.legs:
                    written.append(write_route_bag(out / f"tour_{k}.mcap", self.tour_route(k), self.terrain,
                                                   cost=self.cost))
        return written



def _with_charges(tour: RobotTour, q: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The state of charge along ``tour`` against the legs driven, at the mean or at quantile ``q``: at each charging
    stop twice (on arrival, then full), so the profile rises there."""
    soc = tour.soc(q)
    x, y = [0.0], [float(soc[0])]
    for k in range(len(tour.legs)):
        x.append(k + 1.0)
        y.append(float(soc[k + 1]))
        if k in tour.charging_stops:
            x.append(k + 1.0)
            y.append(1.0)
    return np.array(x), np.array(y)
