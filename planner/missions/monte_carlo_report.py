"""A Monte Carlo study of a mission set up from names: plan the lattice route, drive it N times, report (MonteCarloReport)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from energy import Battery
from terrain import TerrainMap
from terrawatt_base.checks import check_instance, check_real
from terrawatt_base.dask_client import Compute
from terrawatt_base.figure_file import draw_figure

from ..cost_spec import CostSpec
from ..planning import plan_route
from ..route import Route
from .mission_report import check_preset_grounds
from .monte_carlo import simulate_missions_mc
from .monte_carlo_result import MonteCarloResult

__all__ = ["MonteCarloReport", "monte_carlo_mission"]


@dataclass(frozen=True)
class MonteCarloReport:
    """The lattice route of a mission driven N times with drawn parameters, checked against the battery.

    Made by :func:`monte_carlo_mission`. :meth:`summary` is the text ``terrawatt mission
    --monte-carlo N`` prints, :meth:`write` writes monte_carlo.json, .csv and .png.

    Attributes
    ----------
    route : Route
        The lattice route driven (its status says when there is none).
    result : MonteCarloResult or None
        The missions; None when there is no route.
    battery : Battery
        The nominal battery.
    map_label, robot : str
        How the map is named; the robot preset.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    n : int
        Missions asked for.
    risk_q : float or None
        The quantile of the route's energy forecast checked against the usable battery.
    max_risk_pct : float
        Most missions (%) that may go below the reserve for :attr:`ok`.
    """

    route: Route
    result: MonteCarloResult | None
    battery: Battery
    map_label: str
    robot: str
    start_xy_m: tuple[float, float]
    goal_xy_m: tuple[float, float]
    n: int
    risk_q: float | None = None
    max_risk_pct: float = 5.0

    @property
    def risk_need_j(self) -> float | None:
        """The route energy's :attr:`risk_q` quantile (J, of the forecast), or None without ``risk_q`` or result."""
        if self.risk_q is None or self.result is None:
            return None
        return self.result.forecast.quantile_j(self.risk_q)

    @property
    def fits(self) -> bool:
        """Whether :attr:`risk_need_j` fits the usable battery (True without ``risk_q``)."""
        need = self.risk_need_j
        return need is None or need <= self.battery.usable_energy_wh * 3600.0

    @property
    def ok(self) -> bool:
        """A route was driven, at most ``max_risk_pct`` % of the missions went below the reserve, the quantile
        fits and no mission failed."""
        r = self.result
        return r is not None and 100.0 * r.p_below_reserve <= self.max_risk_pct and self.fits and not r.n_failed

    def summary(self) -> str:
        """What ``terrawatt mission --monte-carlo N`` prints: the battery, the route, the study and the reserve check."""
        b, route = self.battery, self.route
        lines = [f"map: {self.map_label}; robot {self.robot}; battery {b.capacity_ah:g} Ah at {b.voltage_v:g} V, "
                 f"reserve {b.min_reserve_pct:g} %"]
        if self.result is None:
            lines.append(f"no route from {self.start_xy_m} to {self.goal_xy_m}: status {route.status!r}")
            return "\n".join(lines)
        lines += [f"route: {route.length_m:.1f} m, planned {route.energy_wh:.2f} Wh; {self.n} missions",
                  self.result.summary()]
        if self.risk_q is not None:  # the reserve check on the forecast's quantile
            lines.append(f"reserve check at Q = {self.risk_q:g}: the route's {self.risk_q:g} quantile "
                         f"{self.risk_need_j / 3600:.2f} Wh {'fits' if self.fits else 'does NOT fit'} the usable "
                         f"{b.usable_energy_wh:.2f} Wh")
        return "\n".join(lines)

    def write(self, out_dir: str | os.PathLike[str], *, on_figure_error: str = "warn") -> list[Path]:
        """Write monte_carlo.json, monte_carlo.csv and monte_carlo.png into ``out_dir`` (nothing without a route);
        return the files written (a figure that fails warns and is left out)."""
        if self.result is None:
            return []
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        written = [self.result.write_json(out / "monte_carlo.json"), self.result.to_csv(out / "monte_carlo.csv")]
        png = draw_figure(out / "monte_carlo.png", lambda: self.result.plot(out / "monte_carlo.png"),
                          on_error=on_figure_error)
        return written + ([png] if png is not None else [])


def monte_carlo_mission(
    terrain: TerrainMap,
    start_xy_m: tuple[float, float],
    goal_xy_m: tuple[float, float],
    n: int,
    *,
    battery: Battery,
    pricing: CostSpec | None = None,
    seed: int | None = 0,
    draw_from: str = "parameters",
    max_risk_pct: float = 5.0,
    compute: Compute | None = None,
    map_label: str = "map",
) -> MonteCarloReport:
    """Plan the lattice route and drive it ``n`` times with drawn parameters (:func:`simulate_missions_mc`).

    The edges are priced as ``pricing`` says (:meth:`planner.cost_spec.CostSpec.build`, at the
    mean); the route is the lattice planner's; the missions draw
    ground coefficients, payload, capacity fade, internal resistance and speed (or, with
    ``draw_from="model"``, the model's predictive distribution).

    Parameters
    ----------
    terrain : TerrainMap
        The map; its grounds are presets.
    start_xy_m, goal_xy_m : (float, float)
        Start and goal (m).
    n : int
        Missions.
    battery : Battery
        The nominal battery (e.g. :func:`planner.missions.mission_report.mission_battery`).
    pricing : CostSpec, optional
        How the edges are priced and the missions driven (:class:`planner.cost_spec.CostSpec`: the
        robot, its speed, the presets or a saved current model; default ``CostSpec()``); its
        ``risk``, when given, is the quantile of the route energy forecast checked against the
        usable battery (needs a model with an interval).
    seed : int or None
        Seed of the draws and of the route's refinement.
    draw_from : str
        ``"parameters"`` or ``"model"`` (needs a model with an interval).
    max_risk_pct : float
        Most missions (%) below the reserve for :attr:`MonteCarloReport.ok`.
    compute : Compute, optional
        Where the missions run and whether a bar shows (:class:`terrawatt_base.dask_client.Compute`).
    map_label : str
        How the map is named.

    Returns
    -------
    MonteCarloReport
        With ``result`` None when start and goal are not joined.

    Raises
    ------
    InvalidParameterError
        A bad number; ``risk`` or ``draw_from="model"`` with a cost that has no interval.
    UnknownNameError
        A ground of the map without a preset.
    """
    check_preset_grounds(terrain)
    max_risk_pct = check_real("max_risk_pct", max_risk_pct, low=0.0, high=100.0)
    pricing = CostSpec() if pricing is None else check_instance("pricing", pricing, CostSpec)
    battery = check_instance("battery", battery, Battery)
    cost = pricing.build(terrain)
    if pricing.risk is not None or draw_from == "model":
        pricing.needs_interval(cost, also="draw_from")
    route = plan_route(terrain, start_xy_m, goal_xy_m, cost=cost, planner="lattice", seed=seed)
    result = None
    if route.found:
        result = simulate_missions_mc(terrain, route, battery, n, robot=pricing.params, speed_mps=pricing.speed_mps,
                                      seed=seed, compute=compute, cost=cost, draw_from=draw_from)
    return MonteCarloReport(route=route, result=result, battery=battery, map_label=map_label, robot=pricing.robot,
                            start_xy_m=(float(start_xy_m[0]), float(start_xy_m[1])),
                            goal_xy_m=(float(goal_xy_m[0]), float(goal_xy_m[1])), n=n, risk_q=pricing.risk,
                            max_risk_pct=max_risk_pct)
