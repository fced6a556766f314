"""The gap rule of sampled streams: median period, gap steps, the gap factor."""

from __future__ import annotations

from typing import Any

import numpy as np

from terrawatt_base.checks import check_real

__all__ = ["DEFAULT_GAP_FACTOR", "check_gap_factor", "gap_steps", "median_period_s", "merged_gaps"]

#: A step between consecutive samples larger than this many median sampling periods is a
#: gap (used by :meth:`InteractionLog.split_at_gaps` and by the readers' gap check).
DEFAULT_GAP_FACTOR = 5.0


def check_gap_factor(gap_factor: Any) -> float:
    """``gap_factor`` as a float: a finite real number > 1.

    Raises
    ------
    InvalidParameterError
        Not a finite real number, or <= 1.

    Examples
    --------
    >>> check_gap_factor(5)
    5.0
    """
    return check_real("gap_factor", gap_factor, low=1.0, low_inclusive=False)


def median_period_s(t: np.ndarray) -> float:
    """Median step between consecutive timestamps (s); needs at least 2 samples."""
    return float(np.median(np.diff(t)))


def gap_steps(t: np.ndarray, gap_factor: float) -> np.ndarray:
    """Indices ``i`` such that ``t[i+1] - t[i]`` exceeds ``gap_factor`` median periods.

    Streams of fewer than 3 samples have no gap (their median period is the only step).

    Examples
    --------
    >>> gap_steps(np.array([0.0, 0.1, 0.2, 1.2, 1.3]), 5.0).tolist()
    [2]
    """
    if t.size < 3:
        return np.zeros(0, dtype=np.intp)
    d = np.diff(t)
    return np.flatnonzero(d > gap_factor * float(np.median(d)))


def merged_gaps(streams: tuple[np.ndarray, ...], gap_factor: float) -> list[tuple[float, float]]:
    """The gaps of several time vectors, ``(start_s, end_s)`` each, overlapping ones merged.

    Examples
    --------
    >>> merged_gaps((np.array([0.0, 0.1, 0.2, 1.2, 1.3]), np.arange(0.0, 1.31, 0.01)), 5.0)
    [(0.2, 1.2)]
    """
    gaps = sorted((float(t[i]), float(t[i + 1])) for t in streams for i in gap_steps(t, gap_factor))
    merged: list[list[float]] = []
    for a, b in gaps:
        if merged and a < merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    return [(a, b) for a, b in merged]
