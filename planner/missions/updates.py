"""Per-cell comparison of a driven leg and the update decisions of the adaptive loop (reuse, adapt or validate)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from energy import CurrentModel, InteractionLog
from terrain import InvalidParameterError
from terrawatt_base.errors import DataError

from ..learned_cost import predict_currents
from ..registry import CellModelRegistry

__all__ = ["validation_error", "predicted_currents", "best_other_model", "charge_error", "adapted_model", "Comparison",
           "driven_runs", "split_runs"]


def validation_error(model: Any, logs: list[InteractionLog]) -> float:
    """Absolute relative error of the integrated absolute current (both sides) over ``logs``.

    ``|sum |I_pred| dt - sum |I_meas| dt| / sum |I_meas| dt`` (lower is better); the metric
    :func:`~planner.run_adaptive_mission` compares old and new models with.

    Raises
    ------
    InvalidParameterError
        The logs hold no current.
    """
    pred = meas = 0.0
    for log in logs:
        dt = np.gradient(log.time_s)
        p = np.abs(predict_currents(model, log, f"model {model!r:.60}")).sum(axis=1)
        m = np.abs(log.current_left_a) + np.abs(log.current_right_a)
        pred += float(np.sum(p * dt))
        meas += float(np.sum(m * dt))
    if meas <= 0:
        raise InvalidParameterError("validation logs hold no current; cannot validate")
    return abs(pred - meas) / meas


def predicted_currents(registry: CellModelRegistry, log: InteractionLog, rows: np.ndarray,
                       cols: np.ndarray) -> np.ndarray:
    """Each sample's current (A, shape (N, 2)) from the model serving its cell (one predict per model in use)."""
    ids = np.asarray(registry.model_id_map)[rows, cols]
    out = np.empty((len(log), 2))
    for mid in np.unique(ids).tolist():
        sel = ids == mid
        out[sel] = predict_currents(registry.model(mid), log, f"model {mid} ({registry.model_record(mid).name!r})")[sel]
    return out


def best_other_model(
    registry: CellModelRegistry, log: InteractionLog, in_region: np.ndarray, measured_a: np.ndarray,
    dt_s: np.ndarray, serving: tuple[int, ...], min_samples: int,
) -> tuple[int, float] | None:
    """The registry model that best explains the log's samples in a region, unless it alone
    already serves the whole region (``serving``: the ids serving its cells): ``(model id,
    |predicted - measured| / measured)`` of the integrated absolute current (both sides), or
    None with fewer than ``min_samples`` samples or no candidate."""
    if np.count_nonzero(in_region) < min_samples or not np.any(measured_a[in_region]):
        return None
    best: tuple[int, float] | None = None
    for mid in registry.model_ids:
        if tuple(serving) == (mid,):  # assigning it would change nothing
            continue
        pred = predict_currents(registry.model(mid), log, f"model {mid} ({registry.model_record(mid).name!r})")
        err = charge_error(pred, measured_a, dt_s, in_region)
        if best is None or err < best[1]:
            best = (int(mid), err)
    return best


def charge_error(predicted_a: np.ndarray, measured_a: np.ndarray, dt_s: np.ndarray, sel: np.ndarray) -> float:
    """``|Q_pred - Q_meas| / Q_meas`` of the absolute current (both sides) over the samples ``sel``."""
    q_meas = float(np.sum(np.abs(measured_a[sel]).sum(axis=1) * dt_s[sel]))
    q_pred = float(np.sum(np.abs(predicted_a[sel]).sum(axis=1) * dt_s[sel]))
    return abs(q_pred - q_meas) / q_meas


def adapted_model(model: Any, logs: list[InteractionLog], **options: Any) -> CurrentModel | None:
    """``model`` updated in-run on ``logs`` (:meth:`energy.CurrentModel.adapt`: seconds, not a refit), or None.

    The update the loop can try before it refits from scratch: the serving model plus a
    small per-side correction fitted on the leg or the excitation just driven, to be
    validated like a new model (:func:`validation_error` on held-back data). ``model``
    itself is never changed. None when ``model`` is not a fitted current model or the logs
    are too short for the update (``options``: ``method``, ``prior_s``, ``min_seconds``...
    of :class:`energy.AdaptedCurrentModel`).

    Raises
    ------
    InvalidParameterError, UnknownNameError
        Bad ``options`` or ``logs``.
    """
    if not isinstance(model, CurrentModel) or not model.is_fitted:
        return None
    try:
        return model.adapt(logs, **options)
    except DataError:  # too little data for an update: keep the model as it is
        return None


class Comparison:
    """Measured and predicted current of one leg's samples, per cell (:meth:`record` puts them in the registry)."""

    def __init__(self, registry: CellModelRegistry, log: InteractionLog, rows: np.ndarray, cols: np.ndarray) -> None:
        self.log, self.rows, self.cols = log, rows, cols
        self.pred = predicted_currents(registry, log, rows, cols)
        self.meas = np.column_stack([log.current_left_a, log.current_right_a])
        self.dt = np.gradient(log.time_s)

    def record(self, registry: CellModelRegistry) -> None:
        """Add this leg's measured and predicted charge to the cells' evidence."""
        registry.evidence.record(self.rows, self.cols, np.abs(self.meas), np.abs(self.pred), self.dt)


def driven_runs(history: Iterable[tuple[InteractionLog, np.ndarray, np.ndarray]], scope: np.ndarray,
                min_run_s: float = 1.0) -> list[InteractionLog]:
    """The driving inside ``scope`` (a boolean cell mask) of the kept legs ``(log, rows, cols)``:
    contiguous runs of at least ``min_run_s`` seconds, oldest first."""
    runs = []
    for log, rows, cols in history:
        inside = scope[rows, cols]
        if not inside.any():
            continue
        edges = np.flatnonzero(np.diff(np.concatenate(([0], inside.astype(np.int8), [0]))))
        for a, b in zip(edges[::2], edges[1::2]):
            t0, t1 = float(log.time_s[a]), float(log.time_s[b - 1])
            if t1 - t0 >= min_run_s:
                try:
                    runs.append(log.slice(t0, t1 + 1e-9))
                except DataError:  # a window without IMU samples: not usable
                    continue
    return runs


def split_runs(runs: list[InteractionLog], validation_fraction: float) -> tuple[list[InteractionLog], list[InteractionLog]]:
    """The first ``1 - validation_fraction`` of the runs' driving time to fit on, the rest to validate
    on (the run that straddles the cut is cut)."""
    total = sum(float(r.duration_s) for r in runs)
    cut_total = (1.0 - validation_fraction) * total
    train: list[InteractionLog] = []
    held: list[InteractionLog] = []
    acc = 0.0
    for r in runs:
        d = float(r.duration_s)
        if acc + d <= cut_total:
            train.append(r)
        elif acc >= cut_total:
            held.append(r)
        else:
            cut = float(r.time_s[0]) + (cut_total - acc)
            for (a, b), into in (((float(r.time_s[0]), cut), train), ((cut, float(r.time_s[-1]) + 1e-9), held)):
                try:
                    piece = r.slice(a, b)
                except (DataError, InvalidParameterError):  # too short a piece
                    continue
                if len(piece) >= 2:  # a model fits on two drive samples at least
                    into.append(piece)
        acc += d
    return train, held
