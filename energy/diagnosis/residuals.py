"""Current residuals (measured - predicted) of logs and their whole-set gap in mAh, % and A.

A model's *gap* on a set of logs is the charge it misses: the measured minus the predicted
current, integrated over each log's clock and summed over both drive sides and all runs.
Integration follows :func:`energy.metrics.charge_mah` (trapezoid rule). For slicing the gap
by regime, the trapezoid integral is written as a weighted sum over samples: sample ``k``
carries the weight ``w_k = (t_{k+1} - t_{k-1}) / 2`` seconds (half of each neighbouring
step; one half-step at either end), so ``sum_k w_k i_k`` *is* the trapezoid integral and the
gaps of any partition of the samples add up exactly to the whole gap.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_real, fmt_number, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

from ..logs import InteractionLog
from ..metrics import DEFAULT_SECTION_S, charge_mah, section_charges_mah, section_error_pct

__all__ = [
    "AS_PER_MAH",
    "GapSummary",
    "checked_pairs",
    "sample_weights_s",
    "residual_currents_a",
    "sample_gap_mah",
    "gap_summary",
]

#: Ampere-seconds in one milliampere-hour.
AS_PER_MAH = 3.6


def _checked_log(log: Any, where: str) -> InteractionLog:
    if not isinstance(log, InteractionLog):
        raise InvalidParameterError(f"{where} must be an InteractionLog, got {type(log).__name__!r}")
    if len(log) < 2:
        raise DataError(f"{where} has {len(log)} drive sample; a current needs at least 2 samples to integrate")
    return log


def _checked_prediction(log: InteractionLog, predicted_a: Any, where: str) -> np.ndarray:
    p = real_array(where, predicted_a, finite=False)
    n = len(log)
    if p.shape != (n, 2):
        raise InvalidParameterError(
            f"{where} must have shape ({n}, 2) ([left, right] current per drive sample of its log), got {p.shape!r}"
        )
    bad = ~np.isfinite(p)
    if bad.any():
        i = int(np.argmax(bad.any(axis=1)))
        raise DataError(f"{where} must be finite; {int(bad.sum())} NaN/inf value(s), first in row {i}")
    return p


def checked_pairs(logs: Any, predictions: Any) -> tuple[tuple[InteractionLog, ...], tuple[np.ndarray, ...]]:
    """Validated ``(logs, predictions)``: a log (or sequence of logs) with its predicted currents.

    Parameters
    ----------
    logs : InteractionLog or sequence of InteractionLog
        The runs, each with at least 2 drive samples.
    predictions : array_like (N, 2) or sequence of them
        ``[left, right]`` predicted current (A) per drive sample of each log, in the order of
        ``logs`` (a single array goes with a single log).

    Returns
    -------
    logs : tuple of InteractionLog
    predictions : tuple of numpy.ndarray, shape (N_i, 2)
        Float64 copies (the inputs are never modified).

    Raises
    ------
    DataError
        No logs; a log with fewer than 2 samples; a non-finite prediction.
    InvalidParameterError
        Not logs; a different number of predictions and logs; a prediction of the wrong shape.
    """
    if isinstance(logs, InteractionLog):
        logs, predictions = (logs,), (predictions,)
    if isinstance(logs, (str, bytes)) or not isinstance(logs, Sequence):
        raise InvalidParameterError(f"logs must be an InteractionLog or a sequence of them, got {type(logs).__name__!r}")
    if len(logs) == 0:
        raise DataError("logs is empty; a gap needs at least one log")
    if isinstance(predictions, (str, bytes, np.ndarray)) or not isinstance(predictions, Sequence):
        raise InvalidParameterError(
            f"predictions must be a sequence with one (N, 2) array per log, got {type(predictions).__name__!r}"
        )
    if len(predictions) != len(logs):
        raise InvalidParameterError(
            f"predictions must hold one array per log: {len(logs)} log(s), {len(predictions)} prediction(s)"
        )
    checked = tuple(_checked_log(log, f"logs[{i}]") for i, log in enumerate(logs))
    preds = tuple(_checked_prediction(log, p, f"predictions[{i}]") for i, (log, p) in enumerate(zip(checked, predictions)))
    return checked, preds


def sample_weights_s(time_s: Any) -> np.ndarray:
    """Trapezoid weight of each sample (s): half of each neighbouring time step.

    ``sum(w * i)`` is the trapezoid integral of ``i`` over ``time_s`` and ``sum(w)`` the span.

    Raises
    ------
    DataError
        Fewer than 2 samples, non-finite or not strictly increasing times.

    Examples
    --------
    >>> sample_weights_s([0.0, 1.0, 3.0]).tolist()
    [0.5, 1.5, 1.0]
    """
    t = real_array("time_s", time_s, ndim=1, finite=False)
    if t.size < 2 or not np.all(np.isfinite(t)):
        raise DataError(f"time_s must hold at least 2 finite samples, got {t.size} sample(s)")
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise DataError(f"time_s must be strictly increasing; first offending index {int(np.argmax(dt <= 0)) + 1}")
    w = np.zeros_like(t)
    w[:-1] += 0.5 * dt
    w[1:] += 0.5 * dt
    return w


def residual_currents_a(log: InteractionLog, predicted_a: Any) -> np.ndarray:
    """Measured minus predicted current per drive sample and side (A).

    Parameters
    ----------
    log : InteractionLog
        The run (its measured ``current_left_a`` / ``current_right_a``).
    predicted_a : array_like, shape (N, 2)
        ``[left, right]`` predicted current (A) at ``log.time_s``.

    Returns
    -------
    numpy.ndarray, shape (N, 2)
        ``[left, right]`` residual (A), a new array.

    Raises
    ------
    InvalidParameterError
        ``log`` is not an InteractionLog; ``predicted_a`` is not of shape ``(N, 2)``.
    DataError
        A log with fewer than 2 samples; a non-finite prediction.

    Examples
    --------
    >>> import numpy as np
    >>> from energy import InteractionLog
    >>> t = np.arange(3) * 0.5
    >>> log = InteractionLog(t, np.ones(3), np.zeros(3), np.full(3, 2.0), np.full(3, 3.0), t, np.full(3, 9.81))
    >>> residual_currents_a(log, np.full((3, 2), 2.5))[0].tolist()
    [-0.5, 0.5]
    """
    log = _checked_log(log, "log")
    p = _checked_prediction(log, predicted_a, "predicted_a")
    return np.column_stack([log.current_left_a, log.current_right_a]) - p


def sample_gap_mah(log: InteractionLog, predicted_a: Any) -> np.ndarray:
    """The gap carried by each drive sample and side (mAh): residual times trapezoid weight.

    Its sum is the log's whole gap ``charge_mah(measured) - charge_mah(predicted)`` over both
    sides; the sum over any subset of samples is that subset's share.

    Returns
    -------
    numpy.ndarray, shape (N, 2)

    Raises
    ------
    InvalidParameterError, DataError
        As in :func:`residual_currents_a`.
    """
    res = residual_currents_a(log, predicted_a)
    return res * (sample_weights_s(log.time_s) / AS_PER_MAH)[:, None]


@dataclass(frozen=True)
class GapSummary:
    """Whole-set figures of a model's gap on a set of logs (both sides, all runs).

    Attributes
    ----------
    measured_mah, predicted_mah : float
        Integrated measured and predicted current, both sides, all runs (mAh).
    gap_mah : float
        ``measured_mah - predicted_mah`` (positive: the model predicts too little).
    charge_error_pct : float
        ``100 * gap_mah / measured_mah`` (signed).
    section_error_pct : float
        Median over runs of the aggregate section error
        (:func:`energy.metrics.section_error_pct` over both sides' sections); runs with no
        measured charge are left out.
    rmse_a : float
        RMSE of the current over all samples and both sides (A).
    n_runs, n_samples : int
        Logs and drive samples behind the figures.
    duration_s : float
        Summed span of the logs (s).
    """

    measured_mah: float
    predicted_mah: float
    gap_mah: float
    charge_error_pct: float
    section_error_pct: float
    rmse_a: float
    n_runs: int
    n_samples: int
    duration_s: float

    def to_dict(self) -> dict[str, float | int]:
        """The figures as a flat dict (JSON-ready)."""
        return asdict(self)

    def __str__(self) -> str:
        return (
            f"gap {fmt_number(self.gap_mah)} mAh of {fmt_number(self.measured_mah)} mAh measured "
            f"({fmt_number(self.charge_error_pct, 3)} %), section error {fmt_number(self.section_error_pct, 3)} %, "
            f"RMSE {fmt_number(self.rmse_a, 3)} A over {self.n_runs} run(s), {fmt_number(self.duration_s)} s"
        )


def _run_section_error_pct(log: InteractionLog, pred: np.ndarray, section_s: float) -> float:
    truth, model = [], []
    for side, measured in enumerate((log.current_left_a, log.current_right_a)):
        truth.append(section_charges_mah(log.time_s, measured, section_s)[1])
        model.append(section_charges_mah(log.time_s, pred[:, side], section_s)[1])
    q_true, q_pred = np.concatenate(truth), np.concatenate(model)
    if not np.sum(q_true) > 0:
        return math.nan
    return section_error_pct(q_pred, q_true)


def gap_summary(logs: Any, predictions: Any, *, section_s: float = DEFAULT_SECTION_S) -> GapSummary:
    """The gap of predicted currents on a set of logs: mAh, %, section error, RMSE.

    Parameters
    ----------
    logs : InteractionLog or sequence of InteractionLog
    predictions : array_like (N, 2) or sequence of them
        ``[left, right]`` predicted current (A) per drive sample of each log.
    section_s : float
        Section length of the section error (s), > 0; default 8 s as in the paper.

    Returns
    -------
    GapSummary

    Raises
    ------
    DataError
        No logs; a log with fewer than 2 samples; non-finite predictions; logs without drive
        current (measured charge of every run not positive).
    InvalidParameterError
        As in :func:`checked_pairs`; ``section_s`` not a finite number > 0.

    Examples
    --------
    >>> import numpy as np
    >>> from energy import InteractionLog
    >>> t = np.arange(37) * 100.0  # one hour at 0.01 Hz
    >>> log = InteractionLog(t, np.ones(37), np.zeros(37), np.full(37, 2.0), np.full(37, 2.0), t, np.full(37, 9.81))
    >>> s = gap_summary([log], [np.full((37, 2), 1.5)])
    >>> round(s.gap_mah, 6), round(s.charge_error_pct, 6), round(s.rmse_a, 6)
    (1000.0, 25.0, 0.5)
    """
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    logs, preds = checked_pairs(logs, predictions)
    measured = predicted = 0.0
    sq_sum, n_values = 0.0, 0
    section_errors = []
    for log, pred in zip(logs, preds):
        measured += charge_mah(log.time_s, log.current_left_a) + charge_mah(log.time_s, log.current_right_a)
        predicted += charge_mah(log.time_s, pred[:, 0]) + charge_mah(log.time_s, pred[:, 1])
        res = np.column_stack([log.current_left_a, log.current_right_a]) - pred
        sq_sum += float(np.sum(res * res))
        n_values += res.size
        section_errors.append(_run_section_error_pct(log, pred, section_s))
    if not measured > 0:
        raise DataError(
            f"the logs carry no drive current: the measured charge of both sides over {len(logs)} run(s) is "
            f"{fmt_number(measured)} mAh; a gap in % needs a positive measured charge"
        )
    errors = np.asarray(section_errors)
    section = float(np.median(errors[np.isfinite(errors)]))  # some run has charge, as the total is > 0
    return GapSummary(
        measured_mah=float(measured),
        predicted_mah=float(predicted),
        gap_mah=float(measured - predicted),
        charge_error_pct=float(100.0 * (measured - predicted) / measured),
        section_error_pct=section,
        rmse_a=float(math.sqrt(sq_sum / n_values)),
        n_runs=len(logs),
        n_samples=int(sum(len(log) for log in logs)),
        duration_s=float(sum(log.duration_s for log in logs)),
    )
