"""Min-max normalisers and the source method's fixed ranges (v, omega, current)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_bool, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

__all__ = [
    "SOURCE_SPEED_RANGE_MPS",
    "SOURCE_OMEGA_RANGE_RADPS",
    "SOURCE_CURRENT_RANGE_A",
    "MinMaxNormaliser",
]

#: Min-max range of |v| in the source method (m/s).
SOURCE_SPEED_RANGE_MPS = (0.0, 1.0)
#: Min-max range of |omega| in the source method (rad/s).
SOURCE_OMEGA_RANGE_RADPS = (0.0, 1.0)
#: Min-max range of the drive current in the source method (0–10 000 mA, in A).
SOURCE_CURRENT_RANGE_A = (0.0, 10.0)

@dataclass(frozen=True, eq=False)
class MinMaxNormaliser:
    """Min-max scaling ``(x' - low) / (high - low)`` with ``x' = |x|`` when ``absolute``.

    Values outside ``[low, high]`` map outside ``[0, 1]``; nothing is clipped. A column
    with ``high == low`` is scaled by 1 (only shifted).

    Parameters
    ----------
    low, high : array_like
        Per-column (or scalar) range, ``high >= low``.
    absolute : bool
        Take absolute values first (the source method's convention for v, omega, current).

    Examples
    --------
    >>> speed = MinMaxNormaliser(*SOURCE_SPEED_RANGE_MPS, absolute=True)
    >>> speed.transform(np.array([-0.5, 0.25])).tolist()
    [0.5, 0.25]
    """

    low: np.ndarray
    high: np.ndarray
    absolute: bool = False

    def __post_init__(self) -> None:
        low = real_array("low", self.low, finite=False)
        high = real_array("high", self.high, finite=False)
        if low.shape != high.shape or low.ndim > 1:
            raise InvalidParameterError(f"low and high must be scalars or 1-D of one shape, got {low.shape!r} and {high.shape!r}")
        if not (np.all(np.isfinite(low)) and np.all(np.isfinite(high))) or np.any(high < low):
            raise InvalidParameterError(f"low and high must be finite with high >= low, got low={low!r}, high={high!r}")
        check_bool("absolute", self.absolute)
        low.setflags(write=False)
        high.setflags(write=False)
        object.__setattr__(self, "low", low)
        object.__setattr__(self, "high", high)
        object.__setattr__(self, "absolute", bool(self.absolute))

    @property
    def span(self) -> np.ndarray:
        """``high - low`` with zero spans replaced by 1."""
        s = self.high - self.low
        return np.where(s > 0, s, 1.0)

    @classmethod
    def from_data(cls, values: Any, absolute: bool = False, per_column: bool = True) -> MinMaxNormaliser:
        """Fit the range to data: per column of a 2-D array, or one range over everything.

        Raises
        ------
        DataError
            Empty or non-finite data.
        """
        x = real_array("values", values, finite=False)
        if x.size == 0 or not np.all(np.isfinite(x)):
            raise DataError(f"cannot fit a normaliser to empty or non-finite data (shape {x.shape!r})")
        if absolute:
            x = np.abs(x)
        if per_column and x.ndim == 2:
            return cls(x.min(axis=0), x.max(axis=0), absolute)
        return cls(float(x.min()), float(x.max()), absolute)

    def transform(self, values: Any) -> np.ndarray:
        """Scale values (broadcast over the last axis)."""
        x = np.asarray(values, dtype=np.float64)
        if self.absolute:
            x = np.abs(x)
        return (x - self.low) / self.span

    def inverse_transform(self, values: Any) -> np.ndarray:
        """Undo :meth:`transform` (absolute values stay absolute)."""
        return np.asarray(values, dtype=np.float64) * self.span + self.low

    def to_dict(self) -> dict[str, Any]:
        """Plain-types form for checkpoints."""
        return {"low": self.low.tolist(), "high": self.high.tolist(), "absolute": self.absolute}

    @classmethod
    def from_dict(cls, data: Any) -> MinMaxNormaliser:
        """Rebuild from :meth:`to_dict` output.

        Raises
        ------
        InvalidParameterError
            Missing keys or bad values.
        """
        try:
            return cls(data["low"], data["high"], data["absolute"])
        except (KeyError, TypeError) as exc:
            raise InvalidParameterError(f"a normaliser needs keys 'low', 'high', 'absolute', got {data!r:.120}") from exc
