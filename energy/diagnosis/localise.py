"""Where a gap lies: the gap (mAh) split by time section, regime, drive side and map block, ranked.

Each drive sample carries its share of the gap, residual times trapezoid weight
(:func:`~energy.diagnosis.residuals.sample_gap_mah`), so the slices of every dimension add up
exactly to the whole gap of :func:`~energy.diagnosis.residuals.gap_summary`. The dimensions,
in the fixed order of :data:`DIMENSIONS`:

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
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from terrain.checks import check_choice, check_real, fmt_number

from ..logs import InteractionLog
from ..metrics import DEFAULT_SECTION_S
from .regimes import check_terrain, regime_labels
from .residuals import AS_PER_MAH, checked_pairs, sample_weights_s

__all__ = ["DIMENSIONS", "SIDES", "GapShare", "time_labels", "localise_gap", "shares_of"]

#: Dimensions of a localisation table, in order.
DIMENSIONS = ("time", "speed", "turning", "acceleration", "grade", "ground", "side", "space")
#: Labels of the side dimension, in the column order of predictions.
SIDES = ("left", "right")


@dataclass(frozen=True)
class GapShare:
    """One row of a localisation table: the gap in one slice of one dimension.

    Attributes
    ----------
    dimension : str
        One of :data:`DIMENSIONS`.
    label : str
        The slice, e.g. ``"pivot"``, ``"0.5-1 m/s"``, ``"snow"``, ``"run 3, 16-24 s"``.
    gap_mah : float
        Signed gap (measured - predicted charge, mAh) in this slice; both sides except in
        the ``"side"`` dimension.
    share_pct : float
        ``100 * |gap_mah| / sum of |gap_mah|`` over the dimension's slices (0 when the
        dimension has no gap at all).
    n_samples : int
        Drive samples in the slice.
    duration_s : float
        Time in the slice (s): the samples' trapezoid weights.
    n_runs : int
        Runs with samples in the slice.
    """

    dimension: str
    label: str
    gap_mah: float
    share_pct: float
    n_samples: int
    duration_s: float
    n_runs: int

    def to_dict(self) -> dict[str, str | float | int]:
        """The row as a flat dict (JSON-ready)."""
        return asdict(self)

    def __str__(self) -> str:
        return (
            f"{self.dimension}: {self.label}: {fmt_number(self.gap_mah)} mAh ({fmt_number(self.share_pct, 3)} %), "
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


def _rows(dimension: str, labels: np.ndarray, gap: np.ndarray, weight: np.ndarray, run: np.ndarray,
          n_runs_total: int) -> list[GapShare]:
    names, inv = np.unique(labels, return_inverse=True)
    inv = inv.reshape(-1)
    k = names.size
    gap_mah = np.bincount(inv, weights=gap, minlength=k)
    n_samples = np.bincount(inv, minlength=k)
    duration = np.bincount(inv, weights=weight, minlength=k)
    pairs = np.unique(inv * n_runs_total + run)
    n_runs = np.bincount(pairs // n_runs_total, minlength=k)
    return _ranked(dimension, names.tolist(), gap_mah, n_samples, duration, n_runs)


def _ranked(dimension: str, names: list[str], gap_mah: np.ndarray, n_samples: np.ndarray, duration: np.ndarray,
            n_runs: np.ndarray) -> list[GapShare]:
    magnitude = np.abs(gap_mah)
    total = float(np.sum(magnitude))
    share = 100.0 * magnitude / total if total > 0 else np.zeros_like(magnitude)
    order = np.lexsort((np.arange(len(names)), -magnitude))
    return [
        GapShare(dimension=dimension, label=str(names[i]), gap_mah=float(gap_mah[i]), share_pct=float(share[i]),
                 n_samples=int(n_samples[i]), duration_s=float(duration[i]), n_runs=int(n_runs[i]))
        for i in order
    ]


def localise_gap(logs: Any, predictions: Any, *, terrain: Any = None,
                 section_s: float = DEFAULT_SECTION_S) -> tuple[GapShare, ...]:
    """Where the gap of predicted currents lies: every dimension's slices, ranked by ``|gap|``.

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

    Returns
    -------
    tuple of GapShare
        The rows of all :data:`DIMENSIONS` in that order; within a dimension, largest
        ``|gap_mah|`` first. Each dimension's ``gap_mah`` add up to the whole gap and its
        ``duration_s`` to the summed span of the logs.

    Raises
    ------
    DataError
        No logs; a log with fewer than 2 samples; non-finite predictions.
    InvalidParameterError
        Not logs; a different number of predictions and logs; a prediction of the wrong
        shape; ``terrain`` not a TerrainMap; ``section_s`` not a finite number > 0.

    Examples
    --------
    >>> import numpy as np
    >>> from energy import InteractionLog
    >>> t = np.arange(5) * 1.0
    >>> log = InteractionLog(t, np.zeros(5), np.full(5, 0.5), np.full(5, 3.6), np.full(5, 3.6), t, np.full(5, 9.81))
    >>> rows = localise_gap([log], [np.column_stack([np.zeros(5), np.full(5, 3.6)])])
    >>> [(r.label, round(r.gap_mah, 6), round(r.share_pct, 1)) for r in rows if r.dimension == "side"]
    [('left', 4.0, 100.0), ('right', 0.0, 0.0)]
    """
    section_s = check_real("section_s", section_s, low=0.0, low_inclusive=False)
    terrain = check_terrain(terrain)
    logs, preds = checked_pairs(logs, predictions)
    per_dim: dict[str, list[np.ndarray]] = {d: [] for d in DIMENSIONS if d != "side"}
    side_gaps, weights, runs = [], [], []
    for i, (log, pred) in enumerate(zip(logs, preds)):
        w = sample_weights_s(log.time_s)
        measured = np.column_stack([log.current_left_a, log.current_right_a])
        side_gaps.append((measured - pred) * (w / AS_PER_MAH)[:, None])
        weights.append(w)
        runs.append(np.full(len(log), i, dtype=np.intp))
        labels = regime_labels(log, terrain=terrain)
        labels["time"] = time_labels(log, i, section_s)
        for dim in per_dim:
            per_dim[dim].append(labels[dim])
    gap_sides = np.concatenate(side_gaps)
    gap = gap_sides.sum(axis=1)
    weight = np.concatenate(weights)
    run = np.concatenate(runs)
    n_runs = len(logs)
    rows: list[GapShare] = []
    for dim in DIMENSIONS:
        if dim == "side":
            n = np.full(2, gap.size)
            rows += _ranked(dim, list(SIDES), gap_sides.sum(axis=0), n, np.full(2, weight.sum()), np.full(2, n_runs))
        else:
            rows += _rows(dim, np.concatenate(per_dim[dim]), gap, weight, run, n_runs)
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
