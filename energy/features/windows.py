"""Windows over a uniformly sampled stream, stated in samples and in seconds."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_int, check_real
from terrawatt_base.errors import DataError

__all__ = ["DEFAULT_T_INTERVAL_S", "WindowSpec", "window_starts", "sliding_windows"]

#: The source method's window ``t_interval`` (s): 10 samples at 100 Hz.
DEFAULT_T_INTERVAL_S = 0.1

@dataclass(frozen=True)
class WindowSpec:
    """A window over a uniformly sampled stream, stated in samples and in seconds.

    Parameters
    ----------
    length_samples : int
        Samples per window (>= 1).
    stride_samples : int
        Samples between window starts (>= 1).
    rate_hz : float
        Sampling rate of the stream the windows cut (Hz, > 0).

    Examples
    --------
    >>> spec = WindowSpec.from_seconds(0.1, rate_hz=100.0)   # the paper's t_interval
    >>> spec.length_samples, spec.stride_samples, spec.length_s
    (10, 10, 0.1)
    """

    length_samples: int
    stride_samples: int
    rate_hz: float

    def __post_init__(self) -> None:
        check_int("WindowSpec.length_samples", self.length_samples, low=1)
        check_int("WindowSpec.stride_samples", self.stride_samples, low=1)
        object.__setattr__(self, "rate_hz", check_real("WindowSpec.rate_hz", self.rate_hz, low=0.0, low_inclusive=False))
        object.__setattr__(self, "length_samples", int(self.length_samples))
        object.__setattr__(self, "stride_samples", int(self.stride_samples))

    @classmethod
    def from_seconds(cls, length_s: float = DEFAULT_T_INTERVAL_S, rate_hz: float = 100.0,
                     stride_s: float | None = None) -> WindowSpec:
        """Window of ``length_s`` (default the paper's 0.1 s) and stride ``stride_s``
        (default: the length) at ``rate_hz`` (default 100 Hz).

        Lengths are rounded to the nearest whole sample, at least one.

        Raises
        ------
        InvalidParameterError
            Non-positive or non-finite arguments.
        """
        length_s = check_real("length_s", length_s, low=0.0, low_inclusive=False)
        rate_hz = check_real("rate_hz", rate_hz, low=0.0, low_inclusive=False)
        stride_s = length_s if stride_s is None else check_real("stride_s", stride_s, low=0.0, low_inclusive=False)
        return cls(
            length_samples=max(1, int(round(length_s * rate_hz))),
            stride_samples=max(1, int(round(stride_s * rate_hz))),
            rate_hz=rate_hz,
        )

    @property
    def length_s(self) -> float:
        """Window length (s)."""
        return self.length_samples / self.rate_hz

    @property
    def stride_s(self) -> float:
        """Stride between window starts (s)."""
        return self.stride_samples / self.rate_hz


def window_starts(n_samples: int, spec: WindowSpec) -> np.ndarray:
    """Start indices of the windows that cover ``n_samples`` samples.

    Windows start every ``stride_samples``; when the last regular window stops short of the
    end, one more window is aligned with the end, so every sample is covered when the
    stride does not exceed the length.

    Raises
    ------
    DataError
        ``n_samples`` is shorter than one window.
    """
    n = int(n_samples)
    if n < spec.length_samples:
        raise DataError(
            f"the record has {n} samples ({n / spec.rate_hz:.3g} s), shorter than one window of "
            f"{spec.length_samples} samples ({spec.length_s:.3g} s)"
        )
    last = n - spec.length_samples
    starts = np.arange(0, last + 1, spec.stride_samples, dtype=np.intp)
    if starts[-1] != last:
        starts = np.append(starts, last)
    return starts


def sliding_windows(values: Any, spec: WindowSpec, starts: np.ndarray | None = None) -> np.ndarray:
    """Windows of a uniformly sampled array, shape ``(n_windows, length_samples, *rest)``.

    Parameters
    ----------
    values : array_like, shape (N, ...)
    spec : WindowSpec
    starts : numpy.ndarray, optional
        Start indices; default :func:`window_starts`.

    Returns
    -------
    numpy.ndarray
        A copy (safe to modify).
    """
    x = np.asarray(values)
    if starts is None:
        starts = window_starts(x.shape[0], spec)
    idx = starts[:, None] + np.arange(spec.length_samples)[None, :]
    return x[idx]
