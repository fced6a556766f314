"""What the battery pays: a held-out run scored on both sides through the pack, and how honest its interval is.

A per-side charge ratio (:class:`~energy.evaluation.AdaptScore`) is the model's own view; its
90th percentile is dominated by the side that draws least. What a mission pays is the energy
of both sides through the robot's pack, over the whole run. :class:`RunTotal` holds one
forecast of one scored run (or of its remainder) against the measurement:

- the **pack energy** (J): the battery-side power of both drive sides
  (:func:`energy.log_battery_power_w`: each motor's terminal voltage times its current, the
  sensor's rest offset removed, regeneration at the robot's efficiency), drawn through the
  pack's internal resistance (:meth:`energy.Battery.current_a`) and integrated as
  ``V_oc * integral(I_pack dt)``: the energy the cells give, the pack's own loss included;
- the **total charge** (A s) of both motor channels, with the forecast's standard deviation
  (the model's :meth:`~energy.models.CurrentModel.predict_distribution`; NaN for a forecast
  without an interval, such as the gain baseline), whose standardised error ``z`` says
  whether the central 50 / 80 / 95 % intervals held.

:func:`summarise_totals` gives, per protocol, ground (then all), model, schedule and variant
(``unadapted``, ``adapted``, ``gain``), the median and 90th percentile of both errors, the
coverage of each interval level and the median ``|z|`` (0.67 for a calibrated Gaussian).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from terrawatt_base.answer import fmt_fixed, markdown_table
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from ..battery import Battery
from ..budget import log_battery_power_w
from ..logs import InteractionLog
from ..models.base import log_currents
from ..models.forecast import CurrentForecast, central_level
from ..robot import RobotParams
from .adapt_results import finite_percentile
from .intervals import DEFAULT_LEVELS, IntervalRecord, plot_reliability

__all__ = ["RunTotal", "ScoredRun", "VARIANTS", "TOTALS_HEADING", "pack_energy_j", "run_totals", "summarise_totals", "totals_markdown",
           "plot_totals_reliability"]

#: The forecasts a run is scored with: the model as fitted, adapted, and the gain baseline.
VARIANTS = ("unadapted", "adapted", "gain")
_ALL = "all"
#: The line above the battery's table in a result's markdown.
TOTALS_HEADING = ("Both sides through the pack (pack energy, total charge; coverage of the total charge's central "
                  "intervals, % of the forecasts with one):")
_trapezoid = getattr(np, "trapezoid", None) or np.trapz


@dataclass(frozen=True)
class RunTotal:
    """One forecast of a scored run (both sides) against the measurement.

    ``true_j`` / ``pred_j`` the pack energy (J), ``true_as`` / ``mean_as`` the total charge of
    both motor channels (A s), ``sd_as`` the forecast's scale of that charge (NaN: no
    interval) and ``dof`` its degrees of freedom (``inf``: Gaussian; a Student-t on a ground
    the model never drove). ``run`` is the scored run, ``adapt_run`` the run adapted on (the same
    run for the per-ground protocol, whose scored part is the remainder after ``schedule``).
    """

    protocol: str
    ground: str
    run: str
    adapt_run: str
    model: str
    schedule: str
    variant: str
    true_j: float
    pred_j: float
    true_as: float
    mean_as: float
    sd_as: float
    dof: float = math.inf

    def __post_init__(self) -> None:
        if self.variant not in VARIANTS:
            raise UnknownNameError(f"RunTotal.variant must be one of {VARIANTS!r}, got {self.variant!r}")

    @property
    def energy_error_pct(self) -> float:
        """|pred - true| / true of the pack energy (%; NaN when nothing was drawn)."""
        return 100.0 * abs(self.pred_j - self.true_j) / self.true_j if self.true_j > 0 else math.nan

    @property
    def charge_error_pct(self) -> float:
        """|mean - true| / true of the total charge (%; NaN when nothing was drawn)."""
        return 100.0 * abs(self.mean_as - self.true_as) / self.true_as if self.true_as > 0 else math.nan

    @property
    def z(self) -> float:
        """Standardised charge error ``(true - mean) / sd`` (NaN without an interval)."""
        if not self.sd_as > 0:
            return math.nan
        return (self.true_as - self.mean_as) / self.sd_as

    @property
    def level_needed(self) -> float:
        """The least central interval level of the forecast's own predictive that holds the measurement (NaN
        without an interval): covered at level ``L`` when ``<= L``."""
        return float(central_level(self.z, self.dof))

    def to_dict(self) -> dict[str, Any]:
        return asdict(self) | {"energy_error_pct": self.energy_error_pct, "charge_error_pct": self.charge_error_pct,
                               "z": self.z}


@dataclass(frozen=True)
class ScoredRun:
    """Which run a forecast is scored on, and how: the labels every :class:`RunTotal` of one call of
    :func:`run_totals` shares.

    ``protocol`` (``"loo"``, ``"per_ground"``, ``"few_shot"``), ``run`` the scored run, ``adapt_run``
    the run adapted on (``run`` itself leaving one run out), ``model`` its name, ``schedule`` the
    variant leaving one run out or the adapt schedule.

    Raises
    ------
    InvalidParameterError
        A label that is not a non-empty string (the error names it).
    """

    protocol: str
    run: str
    adapt_run: str
    model: str
    schedule: str

    def __post_init__(self) -> None:
        for name in ("protocol", "run", "adapt_run", "model", "schedule"):
            value = getattr(self, name)
            if not isinstance(value, str) or not value:
                raise InvalidParameterError(f"{name} must be a non-empty string, got {value!r:.80}", parameter=name)


def pack_energy_j(log: InteractionLog, currents_a: np.ndarray, robot: RobotParams, battery: Battery | None = None,
                  mask: np.ndarray | None = None) -> float:
    """Energy (J) the pack gives while the two drive sides draw ``currents_a`` (N, 2) along ``log``.

    The drive sides' battery-side power (:func:`energy.log_battery_power_w`, motor
    convention, no electronics: the current models do not forecast them), through the
    pack's internal resistance when ``battery`` has one (default: the robot's nominal
    voltage, an ideal source), over the samples ``mask`` (default all).

    Raises
    ------
    InvalidParameterError
        ``currents_a`` not of shape (len(log), 2) or not finite; a power above the pack's maximum.
    """
    cur = np.asarray(currents_a, dtype=np.float64)
    if cur.shape != (len(log), 2) or not np.all(np.isfinite(cur)):
        raise InvalidParameterError(f"currents_a must be finite, of shape {(len(log), 2)!r}, got shape {cur.shape!r}")
    sel = np.ones(len(log), dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    if np.count_nonzero(sel) < 2:
        return 0.0
    driven = dataclasses.replace(log, current_left_a=cur[:, 0], current_right_a=cur[:, 1])
    power = log_battery_power_w(driven, robot, electronics=False)[sel]
    t = log.time_s[sel]
    if battery is None or battery.internal_resistance_ohm == 0.0:
        return float(_trapezoid(power, t))
    return float(battery.voltage_v * _trapezoid(battery.current_a(power), t))


def run_totals(log: InteractionLog, forecasts: dict[str, tuple[np.ndarray, CurrentForecast | None]],
               scored: ScoredRun, *, robot: RobotParams, battery: Battery | None = None,
               mask: np.ndarray | None = None) -> list[RunTotal]:
    """One :class:`RunTotal` per variant of ``forecasts`` (variant -> (mean currents (N, 2), forecast or None)),
    labelled by ``scored``.

    The forecast gives the charge's standard deviation over ``mask``; None or one without an
    interval gives NaN. The pack energy is booked through ``battery`` (:func:`pack_energy_j`).
    """
    sel = np.ones(len(log), dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    truth = log_currents(log)
    t = log.time_s[sel]
    true_as = float(np.sum(_trapezoid(truth[sel], t, axis=0))) if sel.sum() > 1 else 0.0
    true_j = pack_energy_j(log, truth, robot, battery, sel)
    out = []
    for variant, (mean_a, fc) in forecasts.items():
        mean_as = float(np.sum(_trapezoid(np.asarray(mean_a)[sel], t, axis=0))) if sel.sum() > 1 else 0.0
        sd, dof = math.nan, math.inf
        if fc is not None and fc.has_interval:
            charge = fc.charge(sel)
            sd, dof = float(charge.total_sd_as), charge.dof
        out.append(RunTotal(scored.protocol, str(log.meta.ground_label), scored.run, scored.adapt_run, scored.model,
                            scored.schedule, variant,
                            true_j, pack_energy_j(log, mean_a, robot, battery, sel), true_as, mean_as, sd, dof))
    return out


def summarise_totals(totals: Sequence[RunTotal], levels: Sequence[float] = DEFAULT_LEVELS) -> list[dict[str, Any]]:
    """Per protocol, ground (then ``"all"``), model, schedule and variant: errors and interval coverage.

    Each row: the key fields, ``n``, ``energy_median_pct`` / ``energy_p90_pct``,
    ``charge_median_pct`` / ``charge_p90_pct``, ``n_interval`` (forecasts with an interval),
    ``coverage_<L>_pct`` per level ``L`` (%, of the forecasts with an interval; NaN without
    any) and ``median_abs_z``.
    """
    groups: dict[tuple[str, str, str, str, str], list[RunTotal]] = {}
    for r in totals:
        for g in (r.ground, _ALL):
            groups.setdefault((r.protocol, g, r.model, r.schedule, r.variant), []).append(r)
    order = sorted(groups, key=lambda k: (k[0], k[1] == _ALL, k[1], k[2], k[3], VARIANTS.index(k[4])))
    rows = []
    for key in order:
        rs = groups[key]
        zs = np.array([abs(r.z) for r in rs])
        need = np.array([r.level_needed for r in rs])
        need = need[np.isfinite(zs)]
        zs = zs[np.isfinite(zs)]
        row: dict[str, Any] = dict(zip(("protocol", "ground", "model", "schedule", "variant"), key))
        row |= {"n": len(rs),
                "energy_median_pct": finite_percentile([r.energy_error_pct for r in rs], 50),
                "energy_p90_pct": finite_percentile([r.energy_error_pct for r in rs], 90),
                "charge_median_pct": finite_percentile([r.charge_error_pct for r in rs], 50),
                "charge_p90_pct": finite_percentile([r.charge_error_pct for r in rs], 90),
                "n_interval": int(zs.size)}
        for lv in levels:
            row[f"coverage_{100 * lv:g}_pct"] = 100.0 * float(np.mean(need <= lv)) if zs.size else math.nan
        row["median_abs_z"] = float(np.median(zs)) if zs.size else math.nan
        rows.append(row)
    return rows


def totals_markdown(rows: Sequence[dict[str, Any]], levels: Sequence[float] = DEFAULT_LEVELS) -> str:
    """The battery's table: pack energy and total charge errors, and the intervals' coverage, one row per summary
    (``schedule``: the adapt time, or the leave-one-run-out variant)."""
    def f(*xs: Any, nd: int = 1) -> str:
        return " / ".join(fmt_fixed(x, nd) for x in xs)

    header = ["protocol", "ground", "model", "schedule", "forecast", "runs", "pack energy median / p90 %",
              "total charge median / p90 %", f"coverage {' / '.join(f'{100 * lv:g}' for lv in levels)} %",
              "median \\|z\\|"]
    return "\n".join(markdown_table(header, ([
        r["protocol"], r["ground"], r["model"], r["schedule"], r["variant"], r["n"],
        f(r["energy_median_pct"], r["energy_p90_pct"]), f(r["charge_median_pct"], r["charge_p90_pct"]),
        f(*(r[f"coverage_{100 * lv:g}_pct"] for lv in levels), nd=0), f(r["median_abs_z"], nd=2)] for r in rows),
        left=5)) + "\n"


def plot_totals_reliability(totals: Sequence[RunTotal], ax: Any = None, *, title: str | None = None) -> Any:
    """Observed against nominal coverage of the total-charge intervals, one line per protocol, ground and
    variant (the adapt times pooled); forecasts without an interval are left out."""
    records = [IntervalRecord(f"{r.protocol}, {r.ground}, {r.variant}", r.ground, r.run, r.true_as,
                              r.mean_as, r.sd_as, r.dof) for r in totals if r.sd_as > 0]
    return plot_reliability(records, ax, title=title)
