"""Are the forecast intervals honest? Coverage of held-out charges and the reliability plot.

A model's :meth:`~energy.models.CurrentModel.predict_distribution` gives every charge a
Gaussian forecast (:class:`~energy.models.forecast.ChargeForecast`). On held-out runs the
measured charge falls inside the central ``L`` interval for some fraction of the runs — the
*coverage* — which for an honest interval is ``L``. :func:`charge_record` scores one
forecast against one measured run, :func:`coverage` summarises records per level, and
:func:`plot_reliability` draws observed against nominal coverage per group (known grounds,
new grounds, after adaptation...).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from terrawatt_base import plot_target
from terrawatt_base.checks import check_real
from terrawatt_base.errors import InvalidParameterError

from ..logs import InteractionLog
from ..models.base import CurrentModel, log_currents
from ..models.forecast import central_level

__all__ = ["DEFAULT_LEVELS", "IntervalRecord", "charge_record", "coverage", "plot_reliability"]

#: Central interval levels reported by default.
DEFAULT_LEVELS = (0.5, 0.8, 0.95)
_trapezoid = getattr(np, "trapezoid", None) or np.trapz


@dataclass(frozen=True)
class IntervalRecord:
    """One forecast of a held-out run's total charge (both sides) against the measurement.

    Attributes
    ----------
    group : str
        What the record belongs to (e.g. ``"known ground"``, ``"new ground, 20 s"``).
    ground, run : str
    true_as, mean_as, sd_as : float
        Measured charge, forecast mean and scale (A s).
    dof : float
        The forecast's degrees of freedom (``inf``: Gaussian).
    """

    group: str
    ground: str
    run: str
    true_as: float
    mean_as: float
    sd_as: float
    dof: float = math.inf

    @property
    def z(self) -> float:
        """Standardised error ``(true - mean) / sd`` (inf when the forecast has no spread and misses)."""
        if self.sd_as > 0:
            return (self.true_as - self.mean_as) / self.sd_as
        return 0.0 if self.true_as == self.mean_as else float("inf")

    def to_dict(self) -> dict[str, Any]:
        return asdict(self) | {"z": self.z}


def charge_record(model: CurrentModel, log: InteractionLog, *, group: str, run: str,
                  mask: np.ndarray | None = None) -> IntervalRecord:
    """Score ``model``'s charge forecast of ``log`` (or its samples where ``mask``) against the logged currents.

    Raises
    ------
    InvalidParameterError
        ``log`` has no currents or ``mask`` is of another shape.
    """
    if not log.has_currents:
        raise InvalidParameterError(f"the log of run {run!r} has no currents to score a forecast against")
    fc = model.predict_distribution(log)
    sel = np.ones(len(log), dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
    if sel.shape != (len(log),):
        raise InvalidParameterError(f"mask must have shape {(len(log),)!r}, got {sel.shape!r}")
    q = fc.charge(sel)
    truth = log_currents(log)[sel]
    true_as = float(np.sum(_trapezoid(truth, log.time_s[sel], axis=0))) if sel.sum() > 1 else 0.0
    return IntervalRecord(group, str(log.meta.ground_label), run, true_as, q.total_mean_as, q.total_sd_as, q.dof)


def _levels_needed(records: Sequence[IntervalRecord]) -> np.ndarray:
    """Per record, the least central interval level of its own predictive that holds the measurement."""
    return central_level([r.z for r in records], [r.dof for r in records])


def coverage(records: Sequence[IntervalRecord], levels: Sequence[float] = DEFAULT_LEVELS) -> dict[str, dict[str, float]]:
    """Per group, the fraction of records inside each central interval (keys ``"80 %"``), the count and the median |z|.

    Raises
    ------
    InvalidParameterError
        A level outside (0, 1).
    """
    for lv in levels:
        check_real("level", lv, low=0.0, high=1.0, low_inclusive=False, high_inclusive=False)
    out: dict[str, dict[str, float]] = {}
    for group in dict.fromkeys(r.group for r in records):
        mine = [r for r in records if r.group == group]
        zs = np.array([abs(r.z) for r in mine])
        need = _levels_needed(mine)
        row = {f"{100 * lv:g} %": float(np.mean(need <= lv)) for lv in levels}
        row["n"] = float(zs.size)
        row["median |z|"] = float(np.median(zs))
        out[group] = row
    return out


def plot_reliability(records: Sequence[IntervalRecord], ax: Any = None, *, title: str | None = None) -> Any:
    """Observed against nominal coverage of central intervals, one line per group; returns the axes.

    A line on the diagonal is an honest interval; below it, too narrow; above, too wide.
    Without ``ax`` it draws into a new 4.8 x 4.4 in figure
    (:func:`terrawatt_base.plot_target.new_figure`, no pyplot: the user's backend and open
    figures are left alone); write it with ``ax.figure.savefig(...)``.
    """
    if ax is None:
        _, ax = plot_target.new_figure((4.8, 4.4))
    levels = np.linspace(0.05, 0.95, 19)
    ax.plot([0, 1], [0, 1], color="0.6", lw=1, ls="--", label="honest")
    for group in dict.fromkeys(r.group for r in records):
        need = _levels_needed([r for r in records if r.group == group])
        observed = [float(np.mean(need <= lv)) for lv in levels]
        ax.plot(levels, observed, marker="o", ms=3, label=f"{group} (n = {need.size})")
    ax.set_xlabel("nominal coverage of the central interval")
    ax.set_ylabel("observed coverage (held-out whole-run charge)")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    if title:
        ax.set_title(title, fontsize=9)
    return ax
