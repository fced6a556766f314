"""The last-resort candidate: a small ridge regression of the residual on regime features, labelled "learned"."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..logs import InteractionLog
from .effect_base import Effect, EffectParameter
from .regimes import pivoting

__all__ = ["LEARNED_FEATURES", "LearnedResidualEffect", "regime_features"]

#: Names of the regime features of :func:`regime_features`.
LEARNED_FEATURES: tuple[str, ...] = ("one", "abs_v", "abs_omega", "accel", "abs_accel", "abs_v_omega", "pivot")
_RIDGE = 1e-2  # per sample-count penalty weight


def regime_features(log: InteractionLog) -> np.ndarray:
    """Regime features of each sample (N, 7): 1, |v|, |omega|, dv/dt, |dv/dt|, |v omega|, pivot (0/1,
    :func:`~energy.diagnosis.regimes.pivoting`: the localisation's pivot class)."""
    v, w, t = log.v_mps, log.omega_radps, log.time_s
    acc = np.gradient(v, t) if len(log) > 1 else np.zeros(len(log))
    pivot = np.asarray(pivoting(v, w), dtype=np.float64)
    return np.column_stack([np.ones(len(log)), np.abs(v), np.abs(w), acc, np.abs(acc), np.abs(v * w), pivot])


class LearnedResidualEffect(Effect):
    """``I + X @ coef`` per side with the regime features ``X``, ridge-penalised: no physics, a learned patch."""

    name = "learned_residual"
    kind = "learned"
    parameters = tuple(EffectParameter(f"{f}_{side}", 0.0, -100.0, 100.0, "A")
                       for side in ("left", "right") for f in LEARNED_FEATURES)
    description = "learned residual correction (ridge regression on regime features; last resort)"

    def prepare(self, model: Any, log: InteractionLog) -> np.ndarray:
        return regime_features(log)

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        k = len(LEARNED_FEATURES)
        coef = np.asarray(values, dtype=np.float64).reshape(2, k).T
        return predicted_a + prepared @ coef

    def penalty(self, values: np.ndarray) -> np.ndarray:
        return np.sqrt(_RIDGE) * np.asarray(values, dtype=np.float64)
