"""Velocity command series: the :class:`CommandProfile` every driver and simulator consumes.

A :class:`CommandProfile` is a uniformly sampled series of commanded linear speed and yaw
rate (optionally with the reference pose the commands follow). Builders live beside it:
:func:`energy.excitation_commands` (the paper's excitation pattern) and
:func:`energy.profiles.waypoint_commands` / :func:`energy.drive_profile` (stop-turn-go along a route).
:func:`command_series` and :func:`uniform_step_s` are the checks of a command or log time
series that the truth simulator shares.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import readonly
from terrawatt_base.errors import DataError, InvalidParameterError

__all__ = ["CommandProfile", "command_series", "uniform_step_s", "UNIFORM_TIME_RTOL"]

#: Relative tolerance on the uniformity of a profile's time steps.
UNIFORM_TIME_RTOL = 1e-6


def command_series(name: str, value: Any, n: int | None = None) -> np.ndarray:
    """A finite 1-D float64 copy of ``value`` (of length ``n`` when given).

    Raises
    ------
    InvalidParameterError
        Not numeric, not 1-D, or not of length ``n``.
    DataError
        NaN or infinite samples (the message gives the first one's index).
    """
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be an array of numbers, got {value!r:.80}") from None
    if arr.ndim != 1:
        raise InvalidParameterError(f"{name} must be 1-D, got shape {arr.shape!r}")
    if n is not None and arr.size != n:
        raise InvalidParameterError(f"{name} must have the length of time_s ({n}), got {arr.size}")
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(f"{name} must be finite; {int(bad.sum())} non-finite value(s), first at index {i} ({arr[i]!r})")
    return arr


def uniform_step_s(name: str, t: np.ndarray) -> float:
    """The step of a strictly increasing, uniformly spaced time series ``t`` (s).

    Raises
    ------
    DataError
        Times not strictly increasing, or steps differing by more than
        :data:`UNIFORM_TIME_RTOL` of the mean step.
    """
    d = np.diff(t)
    if np.any(d <= 0):
        i = int(np.argmax(d <= 0)) + 1
        raise DataError(f"{name} must be strictly increasing; t[{i}]={t[i]!r} follows t[{i - 1}]={t[i - 1]!r}")
    step = float((t[-1] - t[0]) / (t.size - 1))
    dev = np.abs(d - step)
    if np.any(dev > UNIFORM_TIME_RTOL * step + 1e-12):
        i = int(np.argmax(dev)) + 1
        raise DataError(
            f"{name} must be uniformly spaced (step {step!r} s); the step before index {i} is {d[i - 1]!r} s "
            "— resample the commands onto a uniform grid first"
        )
    return step


def _pose(value: Any, n: int) -> np.ndarray:
    try:
        pose = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"pose_xyh must be a numeric (N, 3) array, got {value!r:.80}") from None
    if pose.shape != (n, 3):
        raise InvalidParameterError(f"pose_xyh must have shape ({n}, 3), got {pose.shape!r}")
    if not np.all(np.isfinite(pose)):
        raise DataError("pose_xyh must be finite (no NaN or inf)")
    return pose


def _times(value: Any) -> np.ndarray:
    t = command_series("time_s", value)
    if t.size < 2:
        raise InvalidParameterError(f"time_s must hold at least 2 samples, got {t.size}")
    uniform_step_s("time_s", t)
    return t


@dataclass(frozen=True, eq=False)
class CommandProfile:
    """Commanded linear speed and yaw rate on a uniform time grid.

    Parameters
    ----------
    time_s : array_like, shape (N,)
        Uniformly spaced, strictly increasing sample times (s), N >= 2.
    v_mps : array_like, shape (N,)
        Commanded forward speed (m/s, signed).
    omega_radps : array_like, shape (N,)
        Commanded yaw rate (rad/s, counter-clockwise positive).
    pose_xyh : array_like, shape (N, 3), optional
        Reference pose (x_m, y_m, heading_rad) the commands follow, when known.

    Raises
    ------
    InvalidParameterError
        Wrong shapes or lengths, fewer than 2 samples.
    DataError
        Non-finite values; times not strictly increasing or not uniformly spaced.

    Examples
    --------
    >>> p = CommandProfile([0.0, 0.1, 0.2], [0.0, 0.2, 0.2], [0.0, 0.0, 0.5])
    >>> round(p.dt_s, 6), round(p.duration_s, 6)
    (0.1, 0.2)
    """

    time_s: np.ndarray
    v_mps: np.ndarray
    omega_radps: np.ndarray
    pose_xyh: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = _times(self.time_s)
        object.__setattr__(self, "time_s", readonly(t, np.float64))
        for name in ("v_mps", "omega_radps"):
            arr = command_series(name, getattr(self, name))
            if arr.size != t.size:
                raise InvalidParameterError(f"{name} must have the length of time_s ({t.size}), got {arr.size}")
            object.__setattr__(self, name, readonly(arr, np.float64))
        if self.pose_xyh is not None:
            object.__setattr__(self, "pose_xyh", readonly(_pose(self.pose_xyh, t.size), np.float64))

    def __len__(self) -> int:
        return int(self.time_s.size)

    @property
    def dt_s(self) -> float:
        """Sampling period (s)."""
        return float((self.time_s[-1] - self.time_s[0]) / (self.time_s.size - 1))

    @property
    def duration_s(self) -> float:
        """Last minus first sample time (s)."""
        return float(self.time_s[-1] - self.time_s[0])

    @classmethod
    def from_poses(cls, time_s: Any, pose_xyh: Any) -> CommandProfile:
        """Commands that reproduce a pose trajectory (differentiated, ``numpy.gradient``).

        ``v`` is the velocity projected on the heading (negative when reversing), ``omega``
        the derivative of the unwrapped heading.

        Parameters
        ----------
        time_s : array_like, shape (N,)
            Uniformly spaced times (s).
        pose_xyh : array_like, shape (N, 3)
            x_m, y_m, heading_rad.

        Returns
        -------
        CommandProfile
            With ``pose_xyh`` set.

        Raises
        ------
        InvalidParameterError, DataError
            As for the constructor.
        """
        t = _times(time_s)
        pose = _pose(pose_xyh, t.size)
        heading = np.unwrap(pose[:, 2])
        vx = np.gradient(pose[:, 0], t)
        vy = np.gradient(pose[:, 1], t)
        v = vx * np.cos(heading) + vy * np.sin(heading)
        omega = np.gradient(heading, t)
        return cls(t, v, omega, pose)
