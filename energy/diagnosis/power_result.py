"""The power stage's result: the battery-power gap, electrical effect scores, waterfall in energy, verdict."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from terrawatt_base.checks import fmt_number

from ..logs import InteractionLog
from ..metrics import DEFAULT_SECTION_S, section_charges_mah, section_error_pct
from ..robot import RobotParams
from .gap import sample_weights_s
from .result import EffectScore

__all__ = ["PowerGapSummary", "PowerWaterfallStep", "PowerDiagnosis", "power_gap_summary"]

_S_PER_H = 3600.0


@dataclass(frozen=True)
class PowerGapSummary:
    """Whole-set figures of a battery-power prediction on a set of logs.

    Attributes
    ----------
    measured_wh, predicted_wh, gap_wh : float
        Integrated measured (voltage x pack current) and predicted battery power, all runs,
        and their difference (Wh; positive: the prediction is too low).
    energy_error_pct : float
        ``100 * gap_wh / measured_wh`` (signed).
    section_error_pct : float
        Median over runs of the aggregate section error of the energy (sections of
        ``section_s``, 8 s by default).
    rmse_w : float
        RMSE of the battery power over all samples (W).
    stopped_gap_pct, stopped_time_pct : float
        Share of ``gap_wh`` while the robot stands still, and of the time it does (%).
    n_runs, n_samples : int
    """

    measured_wh: float
    predicted_wh: float
    gap_wh: float
    energy_error_pct: float
    section_error_pct: float
    rmse_w: float
    stopped_gap_pct: float
    stopped_time_pct: float
    n_runs: int
    n_samples: int

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return asdict(self)


def power_gap_summary(logs: Sequence[InteractionLog], predicted_w: Sequence[np.ndarray],
                      stopped: Sequence[np.ndarray], *, section_s: float = DEFAULT_SECTION_S) -> PowerGapSummary:
    """The :class:`PowerGapSummary` of predicted battery power ``(N,)`` per log against the logs'
    measured battery power; ``stopped`` marks the samples at standstill (0/1 per log)."""
    measured = predicted = gap_stopped = t_stopped = t_all = sq = 0.0
    n = 0
    sections = []
    for log, pred, still in zip(logs, predicted_w, stopped):
        meas = np.asarray(log.battery_power_w, dtype=np.float64)
        pred = np.asarray(pred, dtype=np.float64).reshape(-1)
        w = sample_weights_s(log.time_s)
        still = np.asarray(still, dtype=np.float64) > 0.5
        measured += float(w @ meas) / _S_PER_H
        predicted += float(w @ pred) / _S_PER_H
        gap_stopped += float(w[still] @ (meas - pred)[still]) / _S_PER_H
        t_stopped += float(w[still].sum())
        t_all += float(w.sum())
        sq += float(((meas - pred) ** 2).sum())
        n += meas.size
        q_true = section_charges_mah(log.time_s, meas, section_s)[1]
        q_pred = section_charges_mah(log.time_s, pred, section_s)[1]
        sections.append(section_error_pct(q_pred, q_true) if np.sum(q_true) > 0 else math.nan)
    gap = measured - predicted
    finite = [x for x in sections if math.isfinite(x)]
    return PowerGapSummary(
        measured_wh=measured, predicted_wh=predicted, gap_wh=gap,
        energy_error_pct=100.0 * gap / measured if measured > 0 else math.nan,
        section_error_pct=float(np.median(finite)) if finite else math.nan,
        rmse_w=math.sqrt(sq / n) if n else math.nan,
        stopped_gap_pct=100.0 * gap_stopped / gap if gap != 0 else 0.0,
        stopped_time_pct=100.0 * t_stopped / t_all if t_all > 0 else 0.0,
        n_runs=len(logs), n_samples=n,
    )


@dataclass(frozen=True)
class PowerWaterfallStep:
    """The held-out battery-power gap after one more electrical effect: energy error, 8 s section error, RMSE, shrink."""

    label: str
    energy_error_pct: float
    section_error_pct: float
    rmse_w: float
    shrink_pct: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return asdict(self)


@dataclass(frozen=True, eq=False)
class PowerDiagnosis:
    """What the power stage of :func:`energy.diagnosis.diagnose` found (frozen).

    Attributes
    ----------
    before, after : PowerGapSummary
        Held-out battery-power gap of the model's electrical basis and with the chosen effects.
    ranking : tuple of EffectScore
        Every electrical candidate, as the current stage ranks its own (shrink of the squared
        held-out power residual).
    chosen : tuple of str
    waterfall : tuple of PowerWaterfallStep
    verdict : tuple of str
    fitted : dict of str to dict of str to float
        The chosen effects' values fitted jointly on all logs.
    corrected_robot : RobotParams
        The basis robot with the fitted values (armature resistance, sensor and control powers).
    corrected_effects : tuple of str
        The basis effects plus the chosen ones: ``PhysicsEnergyModel(corrected_robot,
        corrected_effects)`` predicts the battery power with them.
    skipped : dict of str to str
    """

    before: PowerGapSummary
    after: PowerGapSummary
    ranking: tuple[EffectScore, ...]
    chosen: tuple[str, ...]
    waterfall: tuple[PowerWaterfallStep, ...]
    verdict: tuple[str, ...]
    fitted: dict[str, dict[str, float]]
    corrected_robot: RobotParams
    corrected_effects: tuple[str, ...]
    skipped: dict[str, str] = field(default_factory=dict)

    @property
    def found(self) -> bool:
        """Whether an electrical effect explains part of the power gap."""
        return bool(self.chosen)

    def score(self, name: str) -> EffectScore | None:
        """The ranking entry of ``name``, or None."""
        return next((s for s in self.ranking if s.name == name), None)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (the corrected robot by its electrical values)."""
        rb = self.corrected_robot
        return {
            "before": self.before.to_dict(), "after": self.after.to_dict(),
            "ranking": [s.to_dict() for s in self.ranking], "chosen": list(self.chosen),
            "waterfall": [w.to_dict() for w in self.waterfall], "verdict": list(self.verdict),
            "fitted": {k: dict(v) for k, v in self.fitted.items()}, "skipped": dict(self.skipped),
            "corrected_effects": list(self.corrected_effects),
            "corrected_robot": {"name": rb.name, "armature_resistance_ohm": rb.motor.armature_resistance_ohm,
                                "sensor_power_w": rb.sensor_power_w, "sensor_power_per_mps_w": rb.sensor_power_per_mps_w,
                                "control_standby_power_w": rb.control_standby_power_w,
                                "control_stable_power_w": rb.control_stable_power_w},
        }

    def markdown_lines(self, split: str) -> list[str]:
        """The power section of :meth:`Diagnosis.to_markdown`."""
        lines = ["", f"## Battery power: electrical candidates (held-out shrink, split by {split})", "",
                 "Measured battery power = voltage x pack current; predicted from the measured drive currents "
                 "with the model's electrical basis.", "",
                 "| rank | effect | adds | 95 % interval | alone | parameters |", "|---|---|---|---|---|---|"]
        for k, s in enumerate(self.ranking, 1):
            lo, hi = s.added_interval_pct
            params = ", ".join(f"{n} = {fmt_number(v, 4)}" for n, v in s.parameters.items())
            lines.append(f"| {k} | {s.name} | {fmt_number(s.added_pct, 3)} % | {fmt_number(lo, 3)} … "
                         f"{fmt_number(hi, 3)} % | {fmt_number(s.shrink_pct, 3)} % | {params} |")
        lines += ["", "| step | energy error | 8 s section error | RMSE (W) | shrink |", "|---|---|---|---|---|"]
        for w in self.waterfall:
            lines.append(f"| {w.label} | {fmt_number(w.energy_error_pct, 3)} % | {fmt_number(w.section_error_pct, 3)} % "
                         f"| {fmt_number(w.rmse_w, 4)} | {fmt_number(w.shrink_pct, 3)} % |")
        return lines
