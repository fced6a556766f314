"""MonteCarloResult: the per-sample table of a Monte Carlo mission study, its risk of crossing the reserve and energy percentiles.

The answer of :func:`planner.simulate_missions_mc` (the missions of a given route) and of
:func:`planner.missions.monte_carlo_report.monte_carlo_mission` (the same, with the route it planned
and the header a Monte Carlo mission's summary prints: the map, the robot, the reserve check).
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from energy import Battery
from terrawatt_base.answer import write_answer
from terrawatt_base.atomic import write_text_atomic
from terrawatt_base.checks import check_real, readonly, real_array
from terrawatt_base.errors import InvalidParameterError, TerrawattError
from terrawatt_base.formats import result_document, write_result_json

from ..route import Route
from ..route_price import RouteEnergyInterval
from .monte_carlo_figure import plot_monte_carlo
from .monte_carlo_sampling import MissionDistributions

__all__ = ["MonteCarloResult", "MONTE_CARLO_FORMAT_VERSION", "SAMPLE_COLUMNS", "mission_row", "failed_row"]

#: Version of the JSON layout of :meth:`MonteCarloResult.to_dict` (monte_carlo.json; 2: per-sample
#: ``error`` and ``n_failed``).
MONTE_CARLO_FORMAT_VERSION = 2
#: Per-sample numeric columns (besides the ground factors), in CSV order.
SAMPLE_COLUMNS = ("payload_kg", "capacity_ah", "internal_resistance_ohm", "speed_mps", "energy_j", "charge_mah",
                  "duration_s", "arrival_soc", "min_soc")
_FLAGS = ("below_reserve", "depleted")
#: Outcome columns of a mission row (after the drawn ones): energy, charge, duration,
#: arrival and lowest state of charge, the two flags.
_N_OUTCOMES = 7
_SHOWN_ERRORS = 5


def mission_row(drawn: tuple[float, ...], outcome: Callable[[], tuple[float, ...]]) -> tuple[tuple[float, ...], str]:
    """One Monte Carlo mission as ``(row, error)``: the drawn numbers, then ``outcome()``.

    A library error raised by ``outcome`` (a drawn pack that cannot deliver the route's
    power, a drawn robot that cannot follow it, ...) fails this mission alone
    (:func:`failed_row`), as a failed pair's row in :func:`planner.plan_batch`. Any other
    exception propagates out of the mission's task (:func:`planner.simulate_missions_mc` makes
    every mission of a task that fails a failed row).
    """
    try:
        out = outcome()
    except TerrawattError as exc:
        return failed_row(drawn, exc)
    return (*drawn, *out), ""


def failed_row(drawn: tuple[float, ...], exc: BaseException) -> tuple[tuple[float, ...], str]:
    """A mission that failed as ``(row, error)``: the drawn numbers, NaN outcomes (flags false), and
    ``"ExceptionType: message"`` of ``exc``.

    Examples
    --------
    >>> row, error = failed_row((1.0, 2.0), RuntimeError("worker lost"))
    >>> row[:3], row[-2:], error
    ((1.0, 2.0, nan), (0.0, 0.0), 'RuntimeError: worker lost')
    """
    return (*drawn, *([math.nan] * (_N_OUTCOMES - 2)), 0.0, 0.0), f"{type(exc).__name__}: {exc}"


@dataclass(frozen=True, eq=False)
class MonteCarloResult:
    """N missions with drawn parameters: one row per sample, the reserve risk and the energy percentiles.

    Attributes
    ----------
    seed : int or None
        The seed given; ``entropy`` is the seed the samples were drawn from (``seed`` when
        one was given, a fresh one for ``None``): ``seed=entropy`` repeats the study.
    entropy : int
    distributions : MissionDistributions
    battery : Battery
        The nominal battery (each sample fades its capacity and sets its resistance).
    predicted_energy_j : float
        The planner's forecast (nominal parameters, the planner's model): of the driven
        profile when the study had the planning cost, else the route's edge energy.
    ground_names : tuple of str
        Columns of ``ground_scale``.
    ground_scale : ndarray, shape (N, n_grounds)
        Factor drawn for each ground's coefficients.
    payload_kg, capacity_ah, internal_resistance_ohm, speed_mps : ndarray, shape (N,)
        The other drawn parameters (capacity after fade).
    energy_j, charge_mah, duration_s : ndarray, shape (N,)
        Load energy, battery charge and duration of each mission.
    arrival_soc, min_soc : ndarray, shape (N,)
        State of charge at arrival and its lowest value (fractions).
    below_reserve, depleted : ndarray of bool, shape (N,)
        The state of charge went below the reserve; the pack ran empty.
    where : str
        ``"in process"``, ``"local cluster"``, ``"given client"`` or a scheduler address.
    n_workers : int
    elapsed_s : float
    draw_from : {"parameters", "model"}
        What the missions drew: the typed ranges of ``distributions`` (a truth simulation
        each), or the planning model's predictive distribution (``ground_scale`` then holds
        the factor drawn per ground, standard normal or Student-t, ``distributions`` is unused).
    forecast : RouteEnergyInterval or None
        The route's energy distribution on the planning cost when it has an interval (its
        P50 / P90 are in the summary and the JSON).
    errors : tuple of str
        Per sample, ``"ExceptionType: message"`` for a mission that failed with a library
        error (its outcome columns NaN, flags false), else ``""``; empty means none failed.
        The risk and the percentiles are over the completed missions (:attr:`completed`).
    route : Route or None
        The route the study planned and drove (:func:`~planner.missions.monte_carlo_report.monte_carlo_mission`);
        a route that was not found drives no mission (``n == 0``, made by :meth:`no_route`).
    map_label, robot : str
        How the map is named; the robot (its preset name or file), for the header.
    start_xy_m, goal_xy_m : (float, float) or None
        The start and goal the route was asked for.
    risk_q : float or None
        The quantile of the route's energy forecast checked against the usable battery (:attr:`fits`).
    max_risk_pct : float
        Most missions (%) that may go below the reserve for :attr:`ok`.
    """

    seed: int | None
    entropy: int
    distributions: MissionDistributions
    battery: Battery
    predicted_energy_j: float
    ground_names: tuple[str, ...]
    ground_scale: np.ndarray
    payload_kg: np.ndarray
    capacity_ah: np.ndarray
    internal_resistance_ohm: np.ndarray
    speed_mps: np.ndarray
    energy_j: np.ndarray
    charge_mah: np.ndarray
    duration_s: np.ndarray
    arrival_soc: np.ndarray
    min_soc: np.ndarray
    below_reserve: np.ndarray
    depleted: np.ndarray
    where: str = "in process"
    n_workers: int = 1
    elapsed_s: float = math.nan
    draw_from: str = "parameters"
    forecast: RouteEnergyInterval | None = None
    errors: tuple[str, ...] = ()
    route: Route | None = field(default=None, repr=False)
    map_label: str = "map"
    robot: str = ""
    start_xy_m: tuple[float, float] | None = None
    goal_xy_m: tuple[float, float] | None = None
    risk_q: float | None = None
    max_risk_pct: float = 5.0

    @classmethod
    def no_route(cls, route: Route, battery: Battery, **header: Any) -> MonteCarloResult:
        """The study of a route that was not found: no mission driven, the header kept (``header``: the fields from
        ``map_label`` on)."""
        empty = np.empty(0)
        return cls(seed=None, entropy=0, distributions=MissionDistributions(), battery=battery,
                   predicted_energy_j=math.nan, ground_names=(), ground_scale=np.empty((0, 0)),
                   **{c: empty for c in SAMPLE_COLUMNS}, **{f: np.empty(0, dtype=bool) for f in _FLAGS},
                   route=route, **header)

    def __post_init__(self) -> None:
        if self.draw_from not in ("parameters", "model"):
            raise InvalidParameterError(f"draw_from must be 'parameters' or 'model', got {self.draw_from!r}")
        if self.forecast is not None and not isinstance(self.forecast, RouteEnergyInterval):
            raise InvalidParameterError(f"forecast must be a RouteEnergyInterval or None, got {self.forecast!r:.80}")
        n = np.asarray(self.energy_j).shape[0] if np.ndim(self.energy_j) == 1 else -1
        if self.route is not None and not isinstance(self.route, Route):
            raise InvalidParameterError(f"route must be a Route or None, got {type(self.route).__name__!r}")
        unplanned = self.route is not None and not self.route.found
        if n < 1 and not (unplanned and n == 0):
            raise InvalidParameterError("energy_j must be a 1-D array of at least one sample (none only when the "
                                        "route was not found)")
        if unplanned and n:
            raise InvalidParameterError(f"a route that was not found drives no mission, got {n} samples")
        for name in SAMPLE_COLUMNS:
            arr = real_array(name, getattr(self, name), ndim=1, finite=False)
            if arr.shape != (n,):
                raise InvalidParameterError(f"{name} must have shape ({n},), got {arr.shape!r}")
            object.__setattr__(self, name, readonly(arr))
        for name in _FLAGS:
            arr = np.asarray(getattr(self, name))
            if arr.shape != (n,) or arr.dtype != bool:
                raise InvalidParameterError(f"{name} must be a bool array of shape ({n},), got {arr.dtype} {arr.shape!r}")
            object.__setattr__(self, name, readonly(arr))
        scale = real_array("ground_scale", self.ground_scale, ndim=2)
        if scale.shape != (n, len(self.ground_names)):
            raise InvalidParameterError(f"ground_scale must have shape ({n}, {len(self.ground_names)}), got {scale.shape!r}")
        object.__setattr__(self, "ground_scale", readonly(scale))
        object.__setattr__(self, "ground_names", tuple(self.ground_names))
        errors = tuple(self.errors) if self.errors else ("",) * n
        if len(errors) != n or not all(isinstance(e, str) for e in errors):
            raise InvalidParameterError(f"errors must be {n} strings (one per sample) or empty, got {len(errors)}")
        object.__setattr__(self, "errors", errors)
        if any(bool(e) == bool(np.isfinite(x)) for e, x in zip(errors, self.energy_j)):
            raise InvalidParameterError("a sample has error text exactly when its energy_j is not finite")

    @property
    def n(self) -> int:
        """Number of samples (completed and failed)."""
        return int(self.energy_j.shape[0])

    @property
    def failed(self) -> np.ndarray:
        """Per sample: the mission failed with a library error (see :attr:`errors`)."""
        return np.array([bool(e) for e in self.errors], dtype=bool)

    @property
    def n_failed(self) -> int:
        """Number of failed missions."""
        return int(np.count_nonzero(self.failed))

    @property
    def completed(self) -> np.ndarray:
        """Per sample: the mission was driven to its end (the samples the statistics use)."""
        return ~self.failed

    @property
    def p_below_reserve(self) -> float:
        """Fraction of the completed missions whose state of charge went below the reserve (NaN if none completed)."""
        done = self.completed
        return float(np.mean(self.below_reserve[done])) if done.any() else math.nan

    @property
    def p_below_reserve_ci95(self) -> tuple[float, float]:
        """95 % Wilson interval of :attr:`p_below_reserve` (binomial, :func:`scipy.stats.binomtest`)."""
        from scipy.stats import binomtest

        done = self.completed
        if not done.any():
            return math.nan, math.nan
        k = int(np.count_nonzero(self.below_reserve[done]))
        ci = binomtest(k, int(np.count_nonzero(done))).proportion_ci(0.95, method="wilson")
        return float(ci.low), float(ci.high)

    def energy_percentile_j(self, q: float) -> float:
        """The ``q``-th percentile (0-100) of the completed missions' energy (J; linear interpolation; NaN if none)."""
        q = check_real("q", q, low=0.0, high=100.0)
        done = self.energy_j[self.completed]
        return float(np.percentile(done, q)) if done.size else math.nan

    @property
    def energy_percentiles_wh(self) -> dict[str, float]:
        """Mission energy P50, P90 and P99 (Wh)."""
        return {f"p{q}": self.energy_percentile_j(q) / 3600.0 for q in (50, 90, 99)}

    def to_dict(self, *, samples: bool = True) -> dict[str, Any]:
        """Plain JSON-friendly result document, format ``terrawatt-monte-carlo``: the summary and (``samples``) the
        per-sample columns."""
        lo, hi = self.p_below_reserve_ci95
        out: dict[str, Any] = result_document("monte-carlo", MONTE_CARLO_FORMAT_VERSION, {
            "n": self.n,
            "n_failed": self.n_failed,
            "seed": self.seed,
            "entropy": self.entropy,
            "distributions": self.distributions.to_dict(),
            "battery": {"capacity_ah": self.battery.capacity_ah, "voltage_v": self.battery.voltage_v,
                        "min_reserve_pct": self.battery.min_reserve_pct, "initial_soc": self.battery.initial_soc},
            "predicted_energy_wh": self.predicted_energy_j / 3600.0,
            "p_below_reserve": self.p_below_reserve,
            "p_below_reserve_ci95": [lo, hi],
            "p_depleted": float(np.mean(self.depleted)),
            "energy_wh": {**self.energy_percentiles_wh,
                          "mean": float(np.mean(self.energy_j[self.completed])) / 3600.0 if self.n_failed < self.n
                          else math.nan},
            "where": self.where,
            "n_workers": self.n_workers,
            "elapsed_s": self.elapsed_s,
        })
        if self.draw_from == "model":  # files of the typed ranges stay as they were
            out["draw_from"] = "model"
            del out["distributions"]
        if self.forecast is not None:
            out["forecast_interval"] = self.forecast.to_dict()
        if samples:
            out["ground_names"] = list(self.ground_names)
            out["samples"] = {"ground_scale": self.ground_scale.tolist(),
                              **{c: getattr(self, c).tolist() for c in (*SAMPLE_COLUMNS, *_FLAGS)},
                              "error": list(self.errors)}
        return out

    def to_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write the per-sample table (one line per sample, a column per ground factor), atomically."""
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        prefix = "ground_z" if self.draw_from == "model" else "ground_scale"
        writer.writerow(["sample", *(f"{prefix}_{g}" for g in self.ground_names), *SAMPLE_COLUMNS, *_FLAGS, "error"])
        cols = [getattr(self, c) for c in SAMPLE_COLUMNS]
        for i in range(self.n):
            writer.writerow([i, *(repr(float(v)) for v in self.ground_scale[i]), *(repr(float(c[i])) for c in cols),
                             *(str(bool(getattr(self, f)[i])).lower() for f in _FLAGS), self.errors[i]])
        return write_text_atomic(path, buf.getvalue())

    @property
    def risk_need_j(self) -> float | None:
        """The route energy's :attr:`risk_q` quantile (J, of the forecast), or None without ``risk_q`` or missions."""
        if self.risk_q is None or not self.n or self.forecast is None:
            return None
        return self.forecast.quantile_j(self.risk_q)

    @property
    def fits(self) -> bool:
        """Whether :attr:`risk_need_j` fits the usable battery (True without ``risk_q``)."""
        need = self.risk_need_j
        return need is None or need <= self.battery.usable_energy_wh * 3600.0

    @property
    def ok(self) -> bool:
        """Missions were driven, at most ``max_risk_pct`` % went below the reserve, the quantile fits and none failed."""
        return bool(self.n) and 100.0 * self.p_below_reserve <= self.max_risk_pct and self.fits and not self.n_failed

    def summary(self) -> str:
        """What a Monte Carlo mission study prints: with the route's header the map, robot and battery, the
        route, then the study (:meth:`study_summary`) and the reserve check at :attr:`risk_q`."""
        if self.route is None:
            return self.study_summary()
        b, route = self.battery, self.route
        lines = [f"map: {self.map_label}; robot {self.robot}; battery {b.capacity_ah:g} Ah at {b.voltage_v:g} V, "
                 f"reserve {b.min_reserve_pct:g} %"]
        if not route.found:
            lines.append(f"no route from {self.start_xy_m} to {self.goal_xy_m}: status {route.status!r}")
            return "\n".join(lines)
        lines += [f"route: {route.length_m:.1f} m, planned {route.energy_wh:.2f} Wh; {self.n} missions",
                  self.study_summary()]
        if self.risk_q is not None:  # the reserve check on the forecast's quantile
            need = self.risk_need_j
            lines.append(f"reserve check at Q = {self.risk_q:g}: the route's {self.risk_q:g} quantile "
                         f"{math.nan if need is None else need / 3600:.2f} Wh {'fits' if self.fits else 'does NOT fit'} "
                         f"the usable {b.usable_energy_wh:.2f} Wh")
        return "\n".join(lines)

    def write(self, out_dir: str | os.PathLike[str], *, on_figure_error: str = "warn") -> list[Path]:
        """Write monte_carlo.json, monte_carlo.csv and monte_carlo.png into ``out_dir`` (nothing without a mission);
        return the files written (a figure that fails warns and is left out)."""
        if not self.n:
            return []
        return write_answer(out_dir, {"monte_carlo.json": lambda p: write_result_json(p, self.to_dict()),
                                     "monte_carlo.csv": self.to_csv},
                            {"monte_carlo.png": self.plot}, on_figure_error=on_figure_error)

    def study_summary(self) -> str:
        """A few lines for people: the reserve risk and the energy percentiles against the battery."""
        pct = self.energy_percentiles_wh
        lo, hi = self.p_below_reserve_ci95
        b = self.battery
        done = self.completed
        lines = []
        failures = []
        if self.n_failed:
            failures.append(f"{self.n_failed} of {self.n} missions failed (statistics over the "
                            f"{self.n - self.n_failed} completed; the CSV's error column says why):")
            shown = [(i, e) for i, e in enumerate(self.errors) if e][:_SHOWN_ERRORS]
            failures += [f"  mission {i}: {e}" for i, e in shown]
            if self.n_failed > len(shown):
                failures.append(f"  ... and {self.n_failed - len(shown)} more")
        if self.draw_from == "model":
            heavy = self.forecast is not None and any(math.isfinite(self.forecast.ground_dof(g))
                                                      for g in self.forecast.sd_by_ground_j)
            factor = ("one factor per ground (Student-t on a ground the model never drove, else standard normal)"
                      if heavy else "one standard-normal factor per ground")
            lines.append(f"drawn from the planning model's predictive distribution: {factor} "
                         f"({', '.join(self.ground_names) or 'none with a spread'}), edges at mean + z sd")
        if self.forecast is not None:
            f = self.forecast
            lines.append(f"route energy forecast (the model's interval): P50 {f.p50_j / 3600:.2f} Wh, "
                         f"P90 {f.p90_j / 3600:.2f} Wh")
        return "\n".join([
            f"{self.n} missions (seed {self.entropy if self.seed is None else self.seed}) in {self.elapsed_s:.1f} s on "
            f"{self.n_workers} worker(s) ({self.where})",
            *lines,
            f"energy: P50 {pct['p50']:.2f} Wh, P90 {pct['p90']:.2f} Wh, P99 {pct['p99']:.2f} Wh "
            f"(forecast {self.predicted_energy_j / 3600.0:.2f} Wh with nominal parameters)",
            f"below the {b.min_reserve_pct:g} % reserve in {np.count_nonzero(self.below_reserve)} of "
            f"{int(np.count_nonzero(done))} missions: "
            f"P = {100 * self.p_below_reserve:.1f} % (95 % interval {100 * lo:.1f}-{100 * hi:.1f} %); "
            f"battery {b.capacity_ah:g} Ah nominal, {self.capacity_ah.min():.2f}-{self.capacity_ah.max():.2f} Ah after fade",
            *failures,
        ])

    def plot(self, path: str | os.PathLike[str] | None = None, *, ax: Any = None,
             title: str | None = None) -> Path | tuple[Any, ...]:
        """The histogram and exceedance figure (:func:`plot_monte_carlo`).

        Give exactly one of ``path`` (write a PNG atomically and return the path) or
        ``ax`` (2 matplotlib Axes to draw into; nothing is written and they are returned).

        Raises
        ------
        InvalidParameterError
            Both or neither of ``path`` and ``ax``; a bad ``path`` or not 2 axes; every
            mission failed.
        """
        return plot_monte_carlo(self, path, ax=ax, title=title)
