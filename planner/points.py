"""Coordinates in metres as checked ``(N, 2)`` arrays: the one point validator of the planner."""

from __future__ import annotations

from typing import Any

import numpy as np

from terrain.checks import real_array
from terrain.errors import InvalidParameterError

__all__ = ["as_points"]


def as_points(xy: Any, name: str) -> np.ndarray:
    """``xy`` as a float64 ``(N, 2)`` array of finite coordinates (m); a single ``(2,)`` point gives N = 1.

    Raises
    ------
    InvalidParameterError
        Not numbers, another shape, or NaN / inf coordinates (the message names ``name``).
    """
    arr = real_array(name, xy, finite=False)
    if arr.ndim == 1 and arr.shape[0] == 2:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise InvalidParameterError(f"{name} must have shape (N, 2) (x_m, y_m), got shape {arr.shape!r}")
    if not np.all(np.isfinite(arr)):
        bad = arr[~np.all(np.isfinite(arr), axis=1)][0]
        raise InvalidParameterError(f"{name} must be finite coordinates in metres, got {tuple(bad.tolist())!r}")
    return arr
