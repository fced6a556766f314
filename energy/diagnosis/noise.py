"""What a repeat of the runs would scatter: the residual's noise per motion regime, its run-to-run spread, its memory.

The separating drive (:mod:`energy.diagnosis.separating`) and the tie rule
(:func:`energy.diagnosis.selection.tied_with`) both ask how much evidence a difference of
predicted currents is worth against the logs. The answer comes from a model's held-out
residual on the diagnosed runs:

- ``noise_a``: the measured current's white part per logged sample (from consecutive
  differences), overall and per turning regime (standstill, straight, arc, pivot: the sensor
  is noisier where the current is larger);
- ``autocorrelation``: the residual's lag-1 autocorrelation (``kappa = (1 + r) / (1 - r)``:
  correlated samples count less when the per-run means' spread is judged);
- ``run_spread_a``: the spread of the per-run mean residual beyond what the noise explains (a
  per-run offset, which no amount of driving within one run averages away);
- ``residual_a``: the whole residual's RMS (noise and misfit, each run's mean removed), overall
  and per regime: what a new run's gap holds besides the effect looked for.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..logs import InteractionLog
from .regimes import TURNING_LABELS, turning_labels

__all__ = ["ResidualNoise", "residual_noise"]


@dataclass(frozen=True)
class ResidualNoise:
    """A residual's noise (module docstring)."""

    noise_a: float
    run_spread_a: float
    autocorrelation: float
    by_regime: dict[str, float] = field(default_factory=dict)
    residual_a: float = math.nan
    residual_by_regime: dict[str, float] = field(default_factory=dict)

    @property
    def kappa(self) -> float:
        """Samples per independent sample of the residual: ``(1 + r) / (1 - r)`` of its lag-1 autocorrelation."""
        return (1.0 + self.autocorrelation) / (1.0 - self.autocorrelation)

    def per_sample(self, log: InteractionLog) -> np.ndarray:
        """The noise (A) of each drive sample of ``log``: its turning regime's, or the overall one where the
        runs had too few samples of that regime."""
        labels = turning_labels(log)
        return np.array([self.by_regime.get(str(lab), self.noise_a) for lab in labels])

    def residual_per_sample(self, log: InteractionLog) -> np.ndarray:
        """The whole residual's RMS (A; noise and misfit, each run's mean removed) for each drive sample of
        ``log``, by its turning regime: what the model's gap on a new run of it would hold besides the effect."""
        labels = turning_labels(log)
        overall = self.residual_a if math.isfinite(self.residual_a) else self.noise_a
        return np.array([self.residual_by_regime.get(str(lab), overall) for lab in labels])

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dict."""
        return {"noise_a": self.noise_a, "run_spread_a": self.run_spread_a, "autocorrelation": self.autocorrelation,
                "by_regime": dict(self.by_regime), "residual_a": self.residual_a,
                "residual_by_regime": dict(self.residual_by_regime)}


#: Fewest samples of a regime (over all runs) for its own noise figure.
MIN_REGIME_SAMPLES = 30


def _white(abs_steps: np.ndarray) -> float:
    """The white noise (A per sample) behind absolute differences of consecutive samples: a robust
    spread of the differences (1.4826 x the median: a normal's sd), over sqrt(2). A quantised
    sensor whose differences are mostly zero gets at least its quantisation noise's share of
    the mean absolute difference (the median alone would call it noiseless)."""
    if abs_steps.size == 0:
        return 0.0
    robust = 1.4826 * float(np.median(abs_steps))
    floor = math.sqrt(math.pi / 2.0) * float(np.mean(abs_steps)) / 3.0
    return max(robust, floor) / math.sqrt(2.0)


def residual_noise(measured: Sequence[np.ndarray], predicted: Sequence[np.ndarray],
                   logs: Sequence[InteractionLog] | None = None) -> ResidualNoise:
    """The :class:`ResidualNoise` of ``measured - predicted`` (per log, ``(N, sides)``); with ``logs``
    (the same runs) also per turning regime.

    The per-sample noise is the white part of the measured current: the spread of the
    differences of consecutive samples (of one regime, with ``logs``), over ``sqrt(2)``, taken
    robustly (``1.4826 x`` their median absolute value, so that the steps of a start or a stop
    count as the signal they are, not as noise): what a sensor scatters from one
    sample to the next, which repeats average away. A model's misfit is left out: it is a bias
    the next run repeats (a turn priced wrong), and a prediction's own jitter (a term that
    switches sign with a noisy logged yaw rate at standstill) would count the model's
    roughness as the sensor's. ``autocorrelation`` is that of the residual itself (each run's
    mean removed); ``run_spread_a`` the per-run means' spread beyond what the residual's
    scatter explains.
    """
    res = [np.asarray(m, float) - np.asarray(p, float) for m, p in zip(measured, predicted)]
    within = [r - r.mean(axis=0) for r in res]
    steps = [np.diff(np.asarray(m, float), axis=0) for m in measured]
    abs_steps = np.concatenate([np.abs(d) for d in steps]) if steps else np.zeros((0, 2))  # (samples, sides)
    noise = _white(abs_steps)
    num = sum(float(np.sum(w[1:] * w[:-1])) for w in within if len(w) > 1)
    den = sum(float(np.sum(w**2)) for w in within)
    rho = float(np.clip(num / den, 0.0, 0.95)) if den > 0 else 0.0
    spread = 0.0
    if len(res) > 1:
        means = np.array([r.mean(axis=0) for r in res])  # (runs, sides)
        within_var = float(np.mean(np.concatenate([w.ravel() ** 2 for w in within])))
        kappa = (1 + rho) / (1 - rho)
        expect = float(np.mean([within_var * kappa / max(len(r), 1) for r in res]))
        spread = float(math.sqrt(max(float(np.var(means, axis=0, ddof=1).mean()) - expect, 0.0)))
    by_regime: dict[str, float] = {}
    residual_by_regime: dict[str, float] = {}
    if logs is not None:
        same: list[np.ndarray] = []
        labels: list[np.ndarray] = []
        for log in logs:
            lab = turning_labels(log)
            same.append(lab[1:] == lab[:-1])
            labels.append(lab[1:])
        keep, lab = np.concatenate(same), np.concatenate(labels)
        for name in TURNING_LABELS:
            sel = keep & (lab == name)
            if np.count_nonzero(sel) >= MIN_REGIME_SAMPLES:
                by_regime[name] = _white(abs_steps[sel])
        lab_all = np.concatenate([turning_labels(log) for log in logs])
        sq_all = np.concatenate([np.mean(w**2, axis=1) for w in within])
        for name in TURNING_LABELS:
            sel = lab_all == name
            if np.count_nonzero(sel) >= MIN_REGIME_SAMPLES:
                residual_by_regime[name] = float(np.sqrt(np.mean(sq_all[sel])))
    residual = float(np.sqrt(np.mean(np.concatenate([w.ravel() ** 2 for w in within])))) if within else math.nan
    return ResidualNoise(noise, spread, rho, by_regime, residual, residual_by_regime)
