"""Current-estimation metrics: integrated charge (mAh), whole-run and section error %, RMSE.

The vibration-current paper reports the integrated current (mAh) of each drive side over
the whole run and over 8 s sections, and the *error rate*
``|Q_predicted - Q_true| / Q_true * 100``. This module computes those numbers, plus the
aggregate section error ``sum_s |Q_pred,s - Q_true,s| / sum_s Q_true,s * 100`` (one number
per run that does not let a tiny section dominate), the RMSE of the current (A), and the
paper's smoothing, a running median of 100 samples.

Charges are integrated with the trapezoid rule, i.e. exactly for the piecewise-linear current
through the samples. Section boundaries fall between samples: each boundary is inserted as a
sample with the linearly interpolated current and every section is integrated on its own, so
the section charges are exact for that current and add up to the whole-run charge.
Currents are in A inside; mAh only in the names of the reported charges (as in the paper).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage

from terrawatt_base.checks import check_int, check_real, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

__all__ = [
    "DEFAULT_SECTION_S",
    "DEFAULT_SMOOTHING_SAMPLES",
    "CurrentErrors",
    "charge_mah",
    "cumulative_charge_mah",
    "section_charges_mah",
    "error_rate_pct",
    "section_error_pct",
    "rmse_a",
    "moving_median",
    "compare_currents",
]

#: Section length of the paper's per-section errors (s).
DEFAULT_SECTION_S = 8.0
#: Window of the paper's median moving average (samples; 1 s at 100 Hz).
DEFAULT_SMOOTHING_SAMPLES = 100

_AS_PER_MAH = 3.6  # 1 mAh = 3.6 A*s


def _series(time_s: Any, current_a: Any, *, name: str = "current_a") -> tuple[np.ndarray, np.ndarray]:
    t = real_array("time_s", time_s, finite=False)
    i = real_array(name, current_a, finite=False)
    if t.ndim != 1 or t.size < 2:
        raise DataError(f"time_s must be 1-D with at least 2 samples, got shape {t.shape!r}")
    if i.shape != t.shape:
        raise InvalidParameterError(f"{name} must have the shape of time_s {t.shape!r}, got {i.shape!r}")
    if not np.all(np.isfinite(t)) or not np.all(np.isfinite(i)):
        raise DataError(f"time_s and {name} must be finite")
    if np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0)) + 1
        raise DataError(f"time_s must be strictly increasing; first offending index {k} (t={t[k]!r})")
    return t, i


def cumulative_charge_mah(time_s: Any, current_a: Any) -> np.ndarray:
    """Cumulative trapezoid integral of a current from the first sample (mAh).

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Strictly increasing times (s), N >= 2.
    current_a : array_like, shape (N,)
        Current (A).

    Returns
    -------
    numpy.ndarray, shape (N,)
        Charge drawn up to each sample (mAh), starting at 0.

    Raises
    ------
    DataError
        Fewer than 2 samples, non-finite values, timestamps not strictly increasing.
    InvalidParameterError
        ``current_a`` does not have the shape of ``time_s``.
    """
    t, i = _series(time_s, current_a)
    steps = 0.5 * (i[1:] + i[:-1]) * np.diff(t)
    return np.concatenate(([0.0], np.cumsum(steps))) / _AS_PER_MAH


def charge_mah(time_s: Any, current_a: Any) -> float:
    """Integrated current of a whole record (mAh), trapezoid rule.

    Examples
    --------
    >>> charge_mah([0.0, 3600.0], [1.0, 1.0])  # 1 A for one hour
    1000.0
    """
    return float(cumulative_charge_mah(time_s, current_a)[-1])


def section_charges_mah(
    time_s: Any, current_a: Any, section_s: float = DEFAULT_SECTION_S
) -> tuple[np.ndarray, np.ndarray]:
    """Integrated current over consecutive sections of ``section_s`` seconds (mAh).

    Sections start at the first sample: ``[t0, t0 + section_s)``, ``[t0 + section_s, ...)``;
    the last one ends at the last sample and may be shorter (it is kept, so the section
    charges add up to :func:`charge_mah`). Each boundary between samples is inserted with
    the linearly interpolated current and each section is integrated by trapezoid, which is
    the exact charge of the piecewise-linear current through the samples.

    Parameters
    ----------
    time_s, current_a : array_like, shape (N,)
        As in :func:`cumulative_charge_mah`.
    section_s : float
        Section length (s), > 0.

    Returns
    -------
    start_s : numpy.ndarray, shape (S,)
        Start time of each section (s).
    charge_mah : numpy.ndarray, shape (S,)
        Charge of each section (mAh).

    Raises
    ------
    InvalidParameterError
        ``section_s`` is not a finite number > 0.
    DataError
        As in :func:`cumulative_charge_mah`.

    Examples
    --------
    >>> starts, q = section_charges_mah([0.0, 20.0], [3.6, 3.6], section_s=8.0)
    >>> starts.tolist(), [round(x, 6) for x in q.tolist()]
    ([0.0, 8.0, 16.0], [8.0, 8.0, 4.0])
    """
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    t, i = _series(time_s, current_a)
    n_sections = max(1, int(math.ceil((t[-1] - t[0]) / section_s - 1e-9)))
    starts = t[0] + section_s * np.arange(n_sections)
    bounds = np.append(starts, t[-1])
    # samples and boundaries merged in time order; a boundary on a sample comes after it
    merged_t = np.concatenate([t, bounds])
    merged_i = np.concatenate([i, np.interp(bounds, t, i)])
    order = np.argsort(merged_t, kind="stable")
    merged_t, merged_i = merged_t[order], merged_i[order]
    steps = 0.5 * (merged_i[1:] + merged_i[:-1]) * np.diff(merged_t)
    at = np.empty(order.size, dtype=np.intp)
    at[order] = np.arange(order.size)
    edge = at[t.size:]  # merged index of every boundary, increasing
    charge_as = np.add.reduceat(steps[: edge[-1]], edge[:-1])
    return starts, charge_as / _AS_PER_MAH


def error_rate_pct(predicted: Any, truth: Any) -> np.ndarray | float:
    """The paper's error rate ``|predicted - truth| / truth * 100`` (%).

    Parameters
    ----------
    predicted, truth : float or array_like
        Charges (any one unit). Where ``truth`` is 0 the result is NaN (the error rate
        is undefined there).

    Returns
    -------
    float or numpy.ndarray

    Examples
    --------
    >>> error_rate_pct(105.0, 100.0)
    5.0
    """
    p = real_array("predicted", predicted, finite=False)
    q = real_array("truth", truth, finite=False)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(q != 0, np.abs(p - q) / np.abs(np.where(q != 0, q, 1.0)) * 100.0, np.nan)
    return float(out) if out.ndim == 0 else out


def section_error_pct(predicted_mah: Any, truth_mah: Any) -> float:
    """Aggregate section error ``sum |pred_s - truth_s| / sum truth_s * 100`` (%).

    Raises
    ------
    InvalidParameterError
        Shapes differ or are empty.
    DataError
        The total true charge is not positive.
    """
    p = real_array("predicted_mah", predicted_mah, finite=False)
    q = real_array("truth_mah", truth_mah, finite=False)
    if p.shape != q.shape or p.size == 0:
        raise InvalidParameterError(f"predicted and truth must have one non-empty shape, got {p.shape!r} and {q.shape!r}")
    total = float(np.sum(q))
    if not total > 0:
        raise DataError(f"the true charge summed over the sections must be > 0, got {total!r} mAh")
    return float(np.sum(np.abs(p - q)) / total * 100.0)


def rmse_a(predicted_a: Any, truth_a: Any) -> float:
    """Root-mean-square error of a current (A).

    Raises
    ------
    InvalidParameterError
        Shapes differ or are empty.
    """
    p = real_array("predicted_a", predicted_a, finite=False)
    q = real_array("truth_a", truth_a, finite=False)
    if p.shape != q.shape or p.size == 0:
        raise InvalidParameterError(f"predicted and truth must have one non-empty shape, got {p.shape!r} and {q.shape!r}")
    return float(np.sqrt(np.mean((p - q) ** 2)))


def moving_median(values: Any, window_samples: int = DEFAULT_SMOOTHING_SAMPLES) -> np.ndarray:
    """The paper's "median moving average": a centred running median.

    The window is stated in samples (100 samples = 1 s at 100 Hz, 15.4 s at BorealTC's
    6.5 Hz drive rate); near the ends the record is extended with its first/last value
    (``scipy.ndimage.median_filter`` mode ``"nearest"``). Each column of a 2-D array is
    filtered on its own.

    Parameters
    ----------
    values : array_like, shape (N,) or (N, K)
    window_samples : int
        Window length in samples, >= 1.

    Returns
    -------
    numpy.ndarray
        Same shape as ``values``.

    Raises
    ------
    InvalidParameterError
        ``window_samples`` < 1 or not an int; ``values`` not 1-D or 2-D.
    """
    check_int("window_samples", window_samples, low=1)
    x = real_array("values", values, finite=False)
    if x.ndim == 1:
        return ndimage.median_filter(x, size=int(window_samples), mode="nearest")
    if x.ndim == 2:
        return ndimage.median_filter(x, size=(int(window_samples), 1), mode="nearest")
    raise InvalidParameterError(f"values must be 1-D or 2-D, got shape {x.shape!r}")


@dataclass(frozen=True)
class CurrentErrors:
    """How well a predicted current matches the measured one on one record and one side.

    Attributes
    ----------
    charge_true_mah, charge_predicted_mah : float
        Whole-record integrated current (mAh).
    whole_run_error_pct : float
        ``|Q_pred - Q_true| / Q_true * 100``; NaN when ``Q_true`` is 0.
    section_error_pct : float
        ``sum_s |Q_pred,s - Q_true,s| / sum_s Q_true,s * 100`` over ``section_s`` sections;
        NaN when the true charge is not positive.
    section_errors_pct : tuple of float
        Error rate of each section (NaN for sections with zero true charge).
    rmse_a : float
        RMSE of the current (A).
    section_s : float
        Section length (s).
    """

    charge_true_mah: float
    charge_predicted_mah: float
    whole_run_error_pct: float
    section_error_pct: float
    section_errors_pct: tuple[float, ...]
    rmse_a: float
    section_s: float

    def __post_init__(self) -> None:
        if not self.section_s > 0:
            raise InvalidParameterError(f"CurrentErrors.section_s must be > 0, got {self.section_s!r}")
        if not (math.isfinite(self.rmse_a) and self.rmse_a >= 0):
            raise InvalidParameterError(f"CurrentErrors.rmse_a must be finite and >= 0, got {self.rmse_a!r}")
        object.__setattr__(self, "section_errors_pct", tuple(float(x) for x in self.section_errors_pct))


def compare_currents(
    time_s: Any,
    truth_a: Any,
    predicted_a: Any,
    section_s: float = DEFAULT_SECTION_S,
    smoothing_samples: int | None = None,
) -> CurrentErrors:
    """Whole-run and section charge errors and RMSE of one predicted current.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Strictly increasing times (s).
    truth_a, predicted_a : array_like, shape (N,)
        Measured and predicted current (A) at ``time_s``.
    section_s : float
        Section length (s), default 8 s as in the paper.
    smoothing_samples : int, optional
        When given, both currents are first smoothed with :func:`moving_median` of this
        many samples (the paper's plots); ``None`` (default) compares the raw currents.

    Returns
    -------
    CurrentErrors

    Raises
    ------
    DataError, InvalidParameterError
        As in :func:`section_charges_mah` and :func:`rmse_a`.

    Examples
    --------
    >>> t = [0.0, 8.0, 16.0]
    >>> e = compare_currents(t, [2.0, 2.0, 2.0], [2.2, 2.2, 2.2])
    >>> round(e.whole_run_error_pct, 6), round(e.rmse_a, 6)
    (10.0, 0.2)
    """
    t, truth = _series(time_s, truth_a, name="truth_a")
    _, pred = _series(t, predicted_a, name="predicted_a")
    if smoothing_samples is not None:
        truth = moving_median(truth, smoothing_samples)
        pred = moving_median(pred, smoothing_samples)
    q_true = charge_mah(t, truth)
    q_pred = charge_mah(t, pred)
    _, s_true = section_charges_mah(t, truth, section_s)
    _, s_pred = section_charges_mah(t, pred, section_s)
    total = float(np.sum(s_true))
    sec = float(np.sum(np.abs(s_pred - s_true)) / total * 100.0) if total > 0 else math.nan
    return CurrentErrors(
        charge_true_mah=q_true,
        charge_predicted_mah=q_pred,
        whole_run_error_pct=float(error_rate_pct(q_pred, q_true)),
        section_error_pct=sec,
        section_errors_pct=tuple(np.atleast_1d(error_rate_pct(s_pred, s_true)).tolist()),
        rmse_a=rmse_a(pred, truth),
        section_s=float(section_s),
    )
