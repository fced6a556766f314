"""The gap between measured and predicted currents (or battery power): its size (mAh, %, A) and where it lies.

**Its size.** The residuals (measured - predicted current) of logs and their whole-set gap.
A model's *gap* on a set of logs is the charge it misses: the measured minus the predicted
current, integrated over each log's clock and summed over both drive sides and all runs.
Integration follows :func:`energy.metrics.charge_mah` (trapezoid rule). For slicing the gap
by regime, the trapezoid integral is written as a weighted sum over samples: sample ``k``
carries the weight ``w_k = (t_{k+1} - t_{k-1}) / 2`` seconds (half of each neighbouring
step; one half-step at either end), so ``sum_k w_k i_k`` *is* the trapezoid integral and the
gaps of any partition of the samples add up exactly to the whole gap.

The same :class:`GapSummary` and :class:`WaterfallStep` serve every :class:`Quantity` a stage of the
diagnosis explains: :data:`CURRENT` (A, mAh) and :data:`POWER` (the battery power, W, Wh); its units,
words and JSON keys are the quantity's.

**Where it lies.** The net gap (mAh) split by time section, regime, drive side and map block,
ranked (:func:`localise_gap`). Each drive sample carries its share of the gap, residual times
trapezoid weight (:func:`sample_gap_mah`), so the slices of every dimension add up exactly to
the whole gap of :func:`gap_summary`.

A slice is ranked by its **net signed gap**, measured minus predicted charge in mAh
(1 mAh = 3.6 A s; positive: the model predicts too little), largest ``|gap|`` first: a charge,
not a share, so a slice that holds much of the energy weighs as much as it costs, and slices of
opposite sign are shown as such instead of adding up as shares of ``|gap|``. Each slice also
carries its measured charge and the gap as a percentage of it, and a 95 % bootstrap interval
of its net gap: runs are resampled with replacement (the time sections of the run when there
is only one), seeded, so the same inputs give the same interval. A slice found in one run
only gets an interval from 0 to a few times its gap: one run cannot tell whether it recurs.

The dimensions, in the fixed order of :data:`DIMENSIONS`:

- ``"time"`` — contiguous ``section_s`` sections of each run, ``"run 3, 16-24 s"`` (runs
  numbered by their position in ``logs`` from 0; sections start at each run's first sample,
  the last one may be shorter; a sample belongs to the section its timestamp falls in);
- ``"speed"``, ``"turning"``, ``"acceleration"``, ``"grade"``, ``"ground"`` — the regimes
  of :func:`~energy.diagnosis.regimes.regime_labels` (bins stated there);
- ``"side"`` — ``"left"`` and ``"right"`` drive current;
- ``"space"`` — blocks of map cells (needs poses and a ``terrain``, else ``"unknown"``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any, NamedTuple

import numpy as np

from terrawatt_base.checks import check_choice, check_int, check_real, check_seed, fmt_number, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

from ..logs import InteractionLog
from ..metrics import DEFAULT_SECTION_S, section_charges_mah, section_error_pct
from .quantity import AS_PER_MAH, CURRENT, Quantity
from .regimes import UNKNOWN_LABEL, check_terrain, regime_labels

__all__ = [
    "AS_PER_MAH",
    "GapSummary",
    "WaterfallStep",
    "checked_pairs",
    "sample_weights_s",
    "residual_currents_a",
    "sample_gap_mah",
    "gap_summary",
    "DIMENSIONS",
    "SIDES",
    "GAP_INTERVAL_LEVEL",
    "GapShare",
    "time_labels",
    "localise_gap",
    "shares_of",
    "largest_slices",
]

def _checked_log(log: Any, where: str) -> InteractionLog:
    if not isinstance(log, InteractionLog):
        raise InvalidParameterError(f"{where} must be an InteractionLog, got {type(log).__name__!r}")
    if len(log) < 2:
        raise DataError(f"{where} has {len(log)} drive sample; a current needs at least 2 samples to integrate")
    return log


def _checked_prediction(log: InteractionLog, predicted_a: Any, where: str, quantity: Quantity = CURRENT) -> np.ndarray:
    p = real_array(where, predicted_a, finite=False)
    n, c = len(log), len(quantity.columns)
    if c == 1 and p.shape == (n,):
        p = p[:, None]
    if p.shape != (n, c):
        what = "[left, right] current" if quantity is CURRENT else f"the {quantity.name}"
        raise InvalidParameterError(
            f"{where} must have shape ({n}, {c}) ({what} per drive sample of its log), got {p.shape!r}"
        )
    bad = ~np.isfinite(p)
    if bad.any():
        i = int(np.argmax(bad.any(axis=1)))
        raise DataError(f"{where} must be finite; {int(bad.sum())} NaN/inf value(s), first in row {i}")
    return p


def checked_pairs(logs: Any, predictions: Any,
                  quantity: Quantity = CURRENT) -> tuple[tuple[InteractionLog, ...], tuple[np.ndarray, ...]]:
    """Validated ``(logs, predictions)``: a log (or sequence of logs) with its predicted currents (or powers).

    Parameters
    ----------
    logs : InteractionLog or sequence of InteractionLog
        The runs, each with at least 2 drive samples.
    predictions : array_like (N, 2) or sequence of them
        ``[left, right]`` predicted current (A) per drive sample of each log, in the order of
        ``logs`` (a single array goes with a single log); of :data:`POWER`, ``(N,)`` or ``(N, 1)``.
    quantity : Quantity
        What is predicted (default :data:`CURRENT`).

    Returns
    -------
    logs : tuple of InteractionLog
    predictions : tuple of numpy.ndarray, shape (N_i, C)
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
    preds = tuple(_checked_prediction(log, p, f"predictions[{i}]", quantity)
                  for i, (log, p) in enumerate(zip(checked, predictions)))
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


_NAN = float("nan")


@dataclass(frozen=True)
class GapSummary:
    """Whole-set figures of a prediction of one quantity on a set of logs (every column, all runs).

    Attributes
    ----------
    quantity : Quantity
        What was predicted (:data:`CURRENT`, :data:`POWER`): the units of the figures below.
    measured, predicted : float
        Integrated measured and predicted values, every column, all runs (``quantity.total_unit``:
        mAh of current, Wh of battery power).
    gap : float
        ``measured - predicted`` (positive: the model predicts too little).
    error_pct : float
        ``100 * gap / measured`` (signed): the charge or energy error.
    section_error_pct : float
        Median over runs of the aggregate section error
        (:func:`energy.metrics.section_error_pct` over every column's sections); runs with no
        measured total are left out.
    rmse : float
        RMSE over all samples and columns (``quantity.unit``: A, W).
    n_runs, n_samples : int
        Logs and drive samples behind the figures.
    duration_s : float
        Summed span of the logs (s).
    stopped_gap_pct, stopped_time_pct : float
        Share of ``gap`` while the robot stands still, and of the time it does (%), when the
        standstill was given (the power stage); NaN otherwise.
    """

    quantity: Quantity
    measured: float
    predicted: float
    gap: float
    error_pct: float
    section_error_pct: float
    rmse: float
    n_runs: int
    n_samples: int
    duration_s: float
    stopped_gap_pct: float = _NAN
    stopped_time_pct: float = _NAN

    def to_dict(self) -> dict[str, float | int]:
        """The figures as a flat dict (JSON-ready), under the quantity's keys (``measured_mah``, ``rmse_w`` ...)."""
        return {self.quantity.key(f): getattr(self, f) for f in self.quantity.summary_fields}

    def __str__(self) -> str:
        q = self.quantity
        return (
            f"gap {fmt_number(self.gap)} {q.total_unit} of {fmt_number(self.measured)} {q.total_unit} measured "
            f"({fmt_number(self.error_pct, 3)} %), section error {fmt_number(self.section_error_pct, 3)} %, "
            f"RMSE {fmt_number(self.rmse, 3)} {q.unit} over {self.n_runs} run(s), {fmt_number(self.duration_s)} s"
        )


def _run_section_error_pct(log: InteractionLog, measured: np.ndarray, pred: np.ndarray, section_s: float) -> float:
    truth, model = [], []
    for j in range(measured.shape[1]):
        truth.append(section_charges_mah(log.time_s, measured[:, j], section_s)[1])
        model.append(section_charges_mah(log.time_s, pred[:, j], section_s)[1])
    q_true, q_pred = np.concatenate(truth), np.concatenate(model)
    if not np.sum(q_true) > 0:
        return math.nan
    return section_error_pct(q_pred, q_true)


def gap_summary(logs: Any, predictions: Any, *, quantity: Quantity = CURRENT, stopped: Any = None,
                section_s: float = DEFAULT_SECTION_S) -> GapSummary:
    """The gap of a predicted quantity on a set of logs: its total (mAh or Wh), %, section error, RMSE.

    Parameters
    ----------
    logs : InteractionLog or sequence of InteractionLog
    predictions : array_like (N, C) or sequence of them
        Per drive sample of each log, the predicted value of each of the quantity's columns:
        ``[left, right]`` current (A), or the battery power (W; ``(N,)`` will do).
    quantity : Quantity
        :data:`CURRENT` (default; measured: the logged drive currents) or :data:`POWER`
        (measured: the logged battery power).
    stopped : sequence of array_like (N,), optional
        Per log, 1 where the robot stands still: the summary then says which share of the gap
        falls there (``stopped_gap_pct``, ``stopped_time_pct``).
    section_s : float
        Section length of the section error (s), > 0; default 8 s as in the paper.

    Returns
    -------
    GapSummary

    Raises
    ------
    DataError
        No logs; a log with fewer than 2 samples; non-finite predictions; logs without the
        quantity (measured total of every run not positive).
    InvalidParameterError
        As in :func:`checked_pairs`; not a :class:`Quantity`; ``section_s`` not a finite number > 0.

    Examples
    --------
    >>> import numpy as np
    >>> from energy import InteractionLog
    >>> t = np.arange(37) * 100.0  # one hour at 0.01 Hz
    >>> log = InteractionLog(t, np.ones(37), np.zeros(37), np.full(37, 2.0), np.full(37, 2.0), t, np.full(37, 9.81))
    >>> s = gap_summary([log], [np.full((37, 2), 1.5)])
    >>> round(s.gap, 6), round(s.error_pct, 6), round(s.rmse, 6), s.quantity.total_unit
    (1000.0, 25.0, 0.5, 'mAh')
    """
    if not isinstance(quantity, Quantity):
        raise InvalidParameterError(f"quantity must be a Quantity (CURRENT or POWER), got {type(quantity).__name__!r}")
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    logs, preds = checked_pairs(logs, predictions, quantity)
    measured = predicted = gap_stopped = t_stopped = t_all = 0.0
    sq_sum, n_values = 0.0, 0
    section_errors = []
    for k, (log, pred) in enumerate(zip(logs, preds)):
        meas = quantity.measured(log)
        w = sample_weights_s(log.time_s)
        measured += quantity.total(log.time_s, meas, w)
        predicted += quantity.total(log.time_s, pred, w)
        res = meas - pred
        sq_sum += float(np.sum(res * res))
        n_values += res.size
        section_errors.append(_run_section_error_pct(log, meas, pred, section_s))
        if stopped is not None:
            still = np.asarray(stopped[k], dtype=np.float64) > 0.5
            gap_stopped += float(w[still] @ res[still].sum(axis=1)) / quantity.unit_s_per_total
            t_stopped += float(w[still].sum())
            t_all += float(w.sum())
    if not measured > 0:
        what = "drive current" if quantity is CURRENT else "battery power"
        raise DataError(
            f"the logs carry no {what}: the measured {quantity.total_name} of {len(logs)} run(s) is "
            f"{fmt_number(measured)} {quantity.total_unit}; a gap in % needs a positive measured {quantity.total_name}"
        )
    errors = np.asarray(section_errors)
    section = float(np.median(errors[np.isfinite(errors)]))  # some run has a total, as the whole is > 0
    gap = measured - predicted
    shares = {}
    if stopped is not None:
        shares = {"stopped_gap_pct": 100.0 * gap_stopped / gap if gap != 0 else 0.0,
                  "stopped_time_pct": 100.0 * t_stopped / t_all if t_all > 0 else 0.0}
    return GapSummary(
        quantity=quantity,
        measured=float(measured),
        predicted=float(predicted),
        gap=float(gap),
        error_pct=float(100.0 * gap / measured),
        section_error_pct=section,
        rmse=float(math.sqrt(sq_sum / n_values)),
        n_runs=len(logs),
        n_samples=int(sum(len(log) for log in logs)),
        duration_s=float(sum(log.duration_s for log in logs)),
        **shares,
    )


@dataclass(frozen=True)
class WaterfallStep:
    """The held-out gap after one more effect: the error of the total, the 8 s section error, the RMSE, the shrink.

    Attributes
    ----------
    quantity : Quantity
        What the stage explains: the units of ``rmse`` and the keys of :meth:`to_dict`.
    label : str
        ``"as given"``, then ``"+ effect"``.
    error_pct, section_error_pct, rmse, shrink_pct : float
        As in :class:`GapSummary`; ``shrink_pct`` the shrink of the squared held-out gap (%).
    """

    quantity: Quantity
    label: str
    error_pct: float
    section_error_pct: float
    rmse: float
    shrink_pct: float

    @classmethod
    def of(cls, label: str, summary: GapSummary, shrink_pct: float) -> WaterfallStep:
        """The step of a :class:`GapSummary`."""
        return cls(summary.quantity, label, summary.error_pct, summary.section_error_pct, summary.rmse, shrink_pct)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict, under the quantity's keys (``charge_error_pct``, ``rmse_a`` ...)."""
        q = self.quantity
        return {"label": self.label, q.key("error_pct"): self.error_pct, "section_error_pct": self.section_error_pct,
                q.key("rmse"): self.rmse, "shrink_pct": self.shrink_pct}


# ---------------------------------------------------------------------- where the gap lies
#: Dimensions of a localisation table, in order.
DIMENSIONS = ("time", "speed", "turning", "acceleration", "grade", "ground", "side", "space")
#: Labels of the side dimension, in the column order of predictions.
SIDES = ("left", "right")
#: Level of the bootstrap interval of each slice's net gap.
GAP_INTERVAL_LEVEL = 0.95


@dataclass(frozen=True)
class GapShare:
    """One row of a localisation table: the net gap in one slice of one dimension.

    Attributes
    ----------
    dimension : str
        One of :data:`DIMENSIONS`.
    label : str
        The slice, e.g. ``"pivot"``, ``"0.5-1 m/s"``, ``"snow"``, ``"run 3, 16-24 s"``.
    gap_mah : float
        Net signed gap (measured - predicted charge, mAh) in this slice; both sides except in
        the ``"side"`` dimension. The ranking key (largest ``|gap_mah|`` first).
    share_pct : float
        ``100 * |gap_mah| / sum of |gap_mah|`` over the dimension's slices (0 when the
        dimension has no gap at all). Kept for readers of older results; it is a share of
        absolute gaps, large even when opposite slices cancel to a net gap near zero: read
        ``gap_mah`` and ``gap_interval_mah`` instead.
    n_samples : int
        Drive samples in the slice.
    duration_s : float
        Time in the slice (s): the samples' trapezoid weights.
    n_runs : int
        Runs with samples in the slice.
    measured_mah : float
        Measured charge in the slice (mAh; the same sides as ``gap_mah``).
    gap_pct : float
        ``100 * gap_mah / measured_mah`` (signed; NaN when the slice drew no net charge).
    gap_interval_mah : (float, float)
        95 % bootstrap interval of ``gap_mah`` (runs resampled; the time sections of the run
        when there is one; see the module notes).
    """

    dimension: str
    label: str
    gap_mah: float
    share_pct: float
    n_samples: int
    duration_s: float
    n_runs: int
    measured_mah: float = _NAN
    gap_pct: float = _NAN
    gap_interval_mah: tuple[float, float] = (_NAN, _NAN)

    def to_dict(self) -> dict[str, Any]:
        """The row as a flat dict (JSON-ready; the interval as a two-item list)."""
        d = asdict(self)
        d["gap_interval_mah"] = list(self.gap_interval_mah)
        return d

    def __str__(self) -> str:
        lo, hi = self.gap_interval_mah
        return (
            f"{self.dimension}: {self.label}: net {fmt_number(self.gap_mah)} mAh (95 % interval {fmt_number(lo)} … "
            f"{fmt_number(hi)} mAh; {fmt_number(self.gap_pct, 3)} % of its {fmt_number(self.measured_mah)} mAh), "
            f"{self.n_samples} samples, {fmt_number(self.duration_s)} s, {self.n_runs} run(s)"
        )


def _seconds(value: float) -> str:
    return fmt_number(round(value, 3), 9)


def time_labels(log: InteractionLog, run: int, section_s: float = DEFAULT_SECTION_S) -> np.ndarray:
    """Section of each sample, ``"run RUN, a-b s"`` with ``a``, ``b`` from the run's start (s).

    Sections are those of :func:`energy.metrics.section_charges_mah`: ``[k s, (k+1) s)``
    from the first sample, the last one ending at the last sample.

    Raises
    ------
    InvalidParameterError
        ``section_s`` not a finite number > 0.
    """
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    offset = log.time_s - log.time_s[0]
    duration = float(offset[-1])
    n_sections = max(1, int(math.ceil(duration / section_s - 1e-9)))
    k = np.minimum(np.floor(offset / section_s + 1e-9).astype(np.intp), n_sections - 1)
    names = np.asarray(
        [f"run {run}, {_seconds(j * section_s)}-{_seconds(min((j + 1) * section_s, duration))} s" for j in range(n_sections)]
    )
    out = names[k]
    out.setflags(write=False)
    return out


def _bootstrap_units(logs: tuple[InteractionLog, ...], section_s: float) -> list[np.ndarray]:
    """Per log, the unit each drive sample is resampled with: its run, or with one run its time section."""
    if len(logs) > 1:
        return [np.full(len(log), i, dtype=np.intp) for i, log in enumerate(logs)]
    _, inv = np.unique(time_labels(logs[0], 0, section_s), return_inverse=True)
    return [inv.reshape(-1).astype(np.intp)]


def _per_unit(codes: np.ndarray, k: int, unit: np.ndarray, n_units: int, values: np.ndarray) -> np.ndarray:
    """Sum of ``values`` per (slice, unit): a (k, n_units) array."""
    return np.bincount(codes * n_units + unit, weights=values, minlength=k * n_units).reshape(k, n_units)


def _intervals(per_unit: np.ndarray, n_bootstrap: int, seed: int | None) -> tuple[np.ndarray, np.ndarray]:
    """Percentile interval of every row's sum over units resampled with replacement (the same resamples for all)."""
    n_units = per_unit.shape[1]
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, n_units, size=(n_bootstrap, n_units))
    counts = np.zeros((n_bootstrap, n_units))
    np.add.at(counts, (np.arange(n_bootstrap)[:, None], draws), 1.0)
    sums = counts @ per_unit.T  # (n_bootstrap, rows)
    tail = 100.0 * (1.0 - GAP_INTERVAL_LEVEL) / 2.0
    return np.percentile(sums, tail, axis=0), np.percentile(sums, 100.0 - tail, axis=0)


class _Table(NamedTuple):
    """The slices of one dimension: names and per-slice sums, and the gap per (slice, bootstrap unit)."""

    dimension: str
    names: list[str]
    gap_mah: np.ndarray
    n_samples: np.ndarray
    duration_s: np.ndarray
    n_runs: np.ndarray
    measured_mah: np.ndarray
    per_unit: np.ndarray


def _ranked(t: _Table, low: np.ndarray, high: np.ndarray) -> list[GapShare]:
    magnitude = np.abs(t.gap_mah)
    total = float(np.sum(magnitude))
    share = 100.0 * magnitude / total if total > 0 else np.zeros_like(magnitude)
    drew = t.measured_mah > 0
    pct = np.where(drew, 100.0 * t.gap_mah / np.where(drew, t.measured_mah, 1.0), np.nan)
    order = np.lexsort((np.arange(len(t.names)), -magnitude))
    return [
        GapShare(dimension=t.dimension, label=str(t.names[i]), gap_mah=float(t.gap_mah[i]), share_pct=float(share[i]),
                 n_samples=int(t.n_samples[i]), duration_s=float(t.duration_s[i]), n_runs=int(t.n_runs[i]),
                 measured_mah=float(t.measured_mah[i]), gap_pct=float(pct[i]),
                 gap_interval_mah=(float(low[i]), float(high[i])))
        for i in order
    ]


def localise_gap(logs: Any, predictions: Any, *, terrain: Any = None, section_s: float = DEFAULT_SECTION_S,
                 n_bootstrap: int = 200, seed: int | None = 0) -> tuple[GapShare, ...]:
    """Where the gap of predicted currents lies: every dimension's slices, ranked by ``|net gap|``.

    Parameters
    ----------
    logs : InteractionLog or sequence of InteractionLog
        The runs (each with at least 2 drive samples).
    predictions : array_like (N, 2) or sequence of them
        ``[left, right]`` predicted current (A) per drive sample of each log.
    terrain : TerrainMap, optional
        The map the runs drove on; with poses in the logs it gives the grade and space rows.
    section_s : float
        Length of the time sections (s), > 0; default 8 s as in the paper.
    n_bootstrap : int
        Resamples of the slices' 95 % intervals (>= 1).
    seed : int or None
        Seed of the resampling.

    Returns
    -------
    tuple of GapShare
        The rows of all :data:`DIMENSIONS` in that order; within a dimension, largest
        ``|gap_mah|`` (net signed gap) first. Each dimension's ``gap_mah`` add up to the whole
        gap and its ``duration_s`` to the summed span of the logs.

    Raises
    ------
    DataError
        No logs; a log with fewer than 2 samples; non-finite predictions.
    InvalidParameterError
        Not logs; a different number of predictions and logs; a prediction of the wrong
        shape; ``terrain`` not a TerrainMap; ``section_s`` not a finite number > 0; a bad
        ``n_bootstrap`` or ``seed``.

    Examples
    --------
    >>> import numpy as np
    >>> from energy import InteractionLog
    >>> t = np.arange(5) * 1.0
    >>> log = InteractionLog(t, np.zeros(5), np.full(5, 0.5), np.full(5, 3.6), np.full(5, 3.6), t, np.full(5, 9.81))
    >>> rows = localise_gap([log], [np.column_stack([np.zeros(5), np.full(5, 3.6)])])
    >>> [(r.label, round(r.gap_mah, 6), round(r.gap_pct, 1)) for r in rows if r.dimension == "side"]
    [('left', 4.0, 100.0), ('right', 0.0, 0.0)]
    """
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    n_bootstrap = check_int("n_bootstrap", n_bootstrap, low=1)
    seed = check_seed(seed)
    terrain = check_terrain(terrain)
    logs, preds = checked_pairs(logs, predictions)
    unit_parts = _bootstrap_units(logs, section_s)
    per_dim: dict[str, list[np.ndarray]] = {d: [] for d in DIMENSIONS if d != "side"}
    side_gaps, side_measured, weights, runs = [], [], [], []
    for i, (log, pred) in enumerate(zip(logs, preds)):
        w = sample_weights_s(log.time_s)
        measured = np.column_stack([log.current_left_a, log.current_right_a])
        side_gaps.append((measured - pred) * (w / AS_PER_MAH)[:, None])
        side_measured.append(measured * (w / AS_PER_MAH)[:, None])
        weights.append(w)
        runs.append(np.full(len(log), i, dtype=np.intp))
        labels = regime_labels(log, terrain=terrain)
        labels["time"] = time_labels(log, i, section_s)
        for dim in per_dim:
            per_dim[dim].append(labels[dim])
    gap_sides = np.concatenate(side_gaps)
    measured_sides = np.concatenate(side_measured)
    gap = gap_sides.sum(axis=1)
    measured_all = measured_sides.sum(axis=1)
    weight = np.concatenate(weights)
    run = np.concatenate(runs)
    unit = np.concatenate(unit_parts)
    n_runs = len(logs)
    n_units = int(unit.max()) + 1
    tables = []  # per dimension: the slices' names, sums and per-unit gaps
    for dim in DIMENSIONS:
        if dim == "side":
            per_unit = np.stack([np.bincount(unit, weights=gap_sides[:, j], minlength=n_units) for j in range(2)])
            tables.append(_Table(dim, list(SIDES), gap_sides.sum(axis=0), np.full(2, gap.size), np.full(2, weight.sum()),
                                 np.full(2, n_runs), measured_sides.sum(axis=0), per_unit))
            continue
        names, inv = np.unique(np.concatenate(per_dim[dim]), return_inverse=True)
        inv = inv.reshape(-1)
        k = names.size
        pairs = np.unique(inv * n_runs + run)
        tables.append(_Table(dim, names.tolist(), np.bincount(inv, weights=gap, minlength=k),
                             np.bincount(inv, minlength=k), np.bincount(inv, weights=weight, minlength=k),
                             np.bincount(pairs // n_runs, minlength=k), np.bincount(inv, weights=measured_all, minlength=k),
                             _per_unit(inv, k, unit, n_units, gap)))
    low, high = _intervals(np.concatenate([t.per_unit for t in tables]), n_bootstrap, seed)
    rows: list[GapShare] = []
    at = 0
    for t in tables:
        k = len(t.names)
        rows += _ranked(t, low[at:at + k], high[at:at + k])
        at += k
    return tuple(rows)


def shares_of(rows: Any, dimension: str) -> tuple[GapShare, ...]:
    """The rows of one dimension of a localisation table, in their ranked order.

    Raises
    ------
    UnknownNameError
        ``dimension`` is not one of :data:`DIMENSIONS`.
    """
    check_choice("dimension", dimension, DIMENSIONS)
    return tuple(r for r in rows if isinstance(r, GapShare) and r.dimension == dimension)


def largest_slices(rows: Any, n: int = 10) -> tuple[GapShare, ...]:
    """The ``n`` slices of a localisation table with the largest ``|net gap|``, over all dimensions.

    Left out, as they localise nothing: slices labelled ``"unknown"`` and the slices of a
    dimension with fewer than two known, non-empty slices (its one slice holds the whole gap).
    Ties keep the table's order.

    Raises
    ------
    InvalidParameterError
        ``n`` not an int >= 1.

    Examples
    --------
    >>> rows = (GapShare("ground", "snow", 2.0, 80.0, 5, 1.0, 1), GapShare("ground", "grass", -0.5, 20.0, 5, 1.0, 1),
    ...         GapShare("grade", "unknown", 1.5, 100.0, 10, 2.0, 1))
    >>> [r.label for r in largest_slices(rows)]
    ['snow', 'grass']
    """
    n = check_int("n", n, low=1)
    known = [r for r in rows if isinstance(r, GapShare) and r.label != UNKNOWN_LABEL and r.n_samples > 0]
    counts: dict[str, int] = {}
    for r in known:
        counts[r.dimension] = counts.get(r.dimension, 0) + 1
    told = [r for r in known if counts[r.dimension] > 1]
    order = sorted(range(len(told)), key=lambda i: (-abs(told[i].gap_mah), i))
    return tuple(told[i] for i in order[:n])
