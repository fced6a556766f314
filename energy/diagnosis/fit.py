"""Held-out fitting: candidate effects fitted on the calibration data of each fold and scored on its held-out data.

An effect set is fitted with :func:`scipy.optimize.least_squares` on the residual vector of all
calibration samples (every column: both drive sides, or the one battery power) of a fold of the
prepared data's :class:`~energy.diagnosis.case.Split` and scored on that fold's held-out
samples, vectorised; so the pooled held-out squared error of a set is a fair measure of what it
explains. There is no function here that scores a set on the data it was fitted on:
:func:`score_effect_set` scores on the split's folds, which never overlap, and
:func:`fit_effect_set` (used for the final corrected model) returns values, never a score.
:class:`SetRunner` scores many sets, one after another or as tasks on a dask.distributed
client.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import optimize

from terrawatt_base.dask_client import check_client, run_tasks
from terrawatt_base.errors import DataError, InvalidParameterError

from .case import DiagnosisData
from .effect_base import Effect
from .effects import composition_order

__all__ = ["SetScore", "compose", "fit_effect_set", "score_effect_set", "SetRunner"]

def compose(effects: Sequence[Effect], values: Sequence[np.ndarray], base_a: np.ndarray,
            prepared: Sequence[Any], clip: bool, *, surrogate: bool = False) -> np.ndarray:
    """The prediction of one log with ``effects`` added (in composition order), clamped at 0 if ``clip``.

    ``surrogate=True`` (fitting only) uses an effect's ``apply_surrogate`` where it has one:
    a cheap approximation of ``apply`` (the parameter errors interpolate precomputed physics);
    held-out scores and predictions always use the exact ``apply``.
    """
    cur = base_a
    order = sorted(range(len(effects)), key=lambda i: composition_order(effects[i]))
    for i in order:
        e = effects[i]
        apply = e.apply_surrogate if surrogate else e.apply
        cur = apply(np.asarray(values[i], dtype=np.float64), cur, prepared[i])
    return np.maximum(cur, 0.0) if clip else cur


def _unpack(effects: Sequence[Effect], theta: np.ndarray) -> list[np.ndarray]:
    out, k = [], 0
    for e in effects:
        out.append(theta[k:k + e.n_parameters])
        k += e.n_parameters
    return out


def _predict_log(effects: Sequence[Effect], values: Sequence[np.ndarray], data: DiagnosisData, k: int,
                 surrogate: bool = False) -> np.ndarray:
    return compose(effects, values, data.base[k], [data.prepared[e.name][k] for e in effects], data.clip,
                   surrogate=surrogate)


def _fit_rows(effects: Sequence[Effect], data: DiagnosisData, masks: Sequence[np.ndarray] | None,
              start: np.ndarray | None = None) -> list[np.ndarray]:
    """Least-squares values of ``effects`` on the samples selected by ``masks`` (all when None)."""
    n_par = sum(e.n_parameters for e in effects)
    if n_par == 0:
        return [np.zeros(0) for _ in effects]
    rows = [None if masks is None else np.asarray(m) for m in (masks or [None] * len(data.logs))]
    used = [k for k, m in enumerate(rows) if m is None or m.any()]
    n_rows = sum(data.measured[k].shape[0] if rows[k] is None else int(rows[k].sum()) for k in used)
    if data.n_columns * n_rows < n_par:
        names = [e.name for e in effects]
        raise DataError(f"effects {names!r} have {n_par} parameters but the calibration data holds only "
                        f"{data.n_columns * n_rows} measured values")
    lo = np.concatenate([e.bounds[0] for e in effects])
    hi = np.concatenate([e.bounds[1] for e in effects])
    x0 = np.concatenate([e.initial for e in effects]) if start is None else np.clip(start, lo, hi)

    def residual(theta: np.ndarray) -> np.ndarray:
        vals = _unpack(effects, theta)
        parts = []
        for k in used:
            r = _predict_log(effects, vals, data, k, surrogate=True) - data.measured[k]
            parts.append((r if rows[k] is None else r[rows[k]]).ravel())
        parts.extend(e.penalty(v) for e, v in zip(effects, vals))
        return np.concatenate(parts)

    # a non-convex parameter (a lag: the fit of an interpolated shift stops at a kink near its start)
    # is first scanned over its effect's grid, the others held, and the fit starts from the best
    offset = 0
    for e in effects:
        if e.scan and start is None:
            def cost(value: float, i: int = offset) -> float:
                theta = x0.copy()
                theta[i] = value
                return float(np.sum(residual(theta) ** 2))
            grid = [v for v in e.scan if lo[offset] <= v <= hi[offset]]
            if grid:
                x0[offset] = min(grid, key=cost)
        offset += e.n_parameters

    sol = optimize.least_squares(residual, x0, bounds=(lo, hi), method="trf", diff_step=1e-4, x_scale="jac",
                                 max_nfev=200)
    return _unpack(effects, sol.x)


def fit_effect_set(effects: Sequence[Effect], data: DiagnosisData) -> list[np.ndarray]:
    """Values of ``effects`` fitted jointly on all samples of ``data`` (for the final model; no score).

    Raises
    ------
    DataError
        Fewer measured values than parameters.
    """
    return _fit_rows(effects, data, None)


@dataclass(frozen=True, eq=False)
class SetScore:
    """Held-out result of one effect set: squared error per bootstrap unit, the fold values,
    and the held-out prediction of every sample (each from the fold that held it out)."""

    names: tuple[str, ...]
    sse_units: np.ndarray
    n_units_samples: np.ndarray
    fold_values: tuple[tuple[np.ndarray, ...], ...]
    held_out_a: tuple[np.ndarray, ...]
    n_columns: int = 2

    @property
    def mse(self) -> float:
        """Held-out mean squared residual over every measured value (A^2 for currents, W^2 for power)."""
        return float(self.sse_units.sum() / max(self.n_columns * self.n_units_samples.sum(), 1))

    def median_values(self) -> list[np.ndarray]:
        """Per effect, the median over folds of the fitted values."""
        n = len(self.names)
        return [np.median(np.stack([fv[i] for fv in self.fold_values]), axis=0) if self.fold_values else np.zeros(0)
                for i in range(n)]


def score_effect_set(effects: Sequence[Effect], data: DiagnosisData) -> SetScore:
    """Fit ``effects`` jointly on each fold's calibration samples; score them on its held-out samples.

    Raises
    ------
    InvalidParameterError
        ``data`` prepared without a split.
    DataError
        A fold with fewer calibration values than the set has parameters.
    """
    split = data.split
    if split is None:
        raise InvalidParameterError("data must be prepared with a split to score an effect set held out")
    n_logs = len(data.logs)
    held = [np.zeros_like(m) for m in data.measured]
    fold_values = []
    for fold in split.folds:
        vals = _fit_rows(effects, data, fold.calibration) if effects else []
        fold_values.append(tuple(vals))
        for k in range(n_logs):
            h = fold.held_out[k]
            if h.any():
                held[k][h] = _predict_log(effects, vals, data, k)[h]
    sse = np.zeros(split.n_units)
    count = np.zeros(split.n_units)
    for k in range(n_logs):
        sq = ((held[k] - data.measured[k]) ** 2).sum(axis=1)
        sse += np.bincount(split.units[k], weights=sq, minlength=split.n_units)
        count += np.bincount(split.units[k], minlength=split.n_units)
    return SetScore(tuple(e.name for e in effects), sse, count, tuple(fold_values), tuple(held), data.n_columns)


class SetRunner:
    """Scores effect sets on one :class:`~energy.diagnosis.case.DiagnosisData` (and its split), here or on ``client``.

    On a client each batch of sets is one :func:`~terrawatt_base.dask_client.run_tasks` call:
    the data its shared input (sent once per batch, computed again if the workers holding it
    die), each set one task. Results come back in the order asked, equal to the serial ones
    (the fits are deterministic least squares). ``progress`` shows a tqdm bar per batch.
    """

    def __init__(self, data: DiagnosisData, *, client: Any = None, progress: bool = False) -> None:
        self.data = data
        self.client = check_client(client, "candidate effect sets")
        self.progress = bool(progress)

    def score(self, sets: Sequence[Sequence[Effect]], desc: str = "effect sets") -> list[SetScore]:
        """The held-out score of each set in ``sets``, in order."""
        tasks = [(_score_with, (list(s),)) for s in sets]
        client = self.client if len(sets) >= 2 else None
        return list(run_tasks(tasks, client=client, shared=(self.data,), progress=self.progress, description=desc))


def _score_with(data: DiagnosisData, effects: Sequence[Effect]) -> SetScore:
    """:func:`score_effect_set` with the shared input first (a task of :meth:`SetRunner.score`)."""
    return score_effect_set(effects, data)
