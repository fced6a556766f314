"""Validation of an interaction log's arrays: the stream fields, finite vectors, increasing times, pose, labels."""

from __future__ import annotations

from typing import Any

import numpy as np

from terrawatt_base.checks import fmt_number, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

__all__ = [
    "DRIVE_FIELDS",
    "IMU_FIELDS",
    "OPTIONAL_FIELDS",
    "log_vector",
    "stream_vector",
    "check_increasing",
    "pose_array",
    "ground_array",
]

#: Per-sample arrays of the drive stream (on ``time_s``).
DRIVE_FIELDS = ("v_mps", "omega_radps", "current_left_a", "current_right_a", "battery_voltage_v", "battery_current_a")
#: Per-sample arrays of the IMU stream (on ``accel_time_s``).
IMU_FIELDS = ("accel_z_mps2", "gyro_z_radps")
#: The stream arrays a log may lack (``None``); the two currents come together or not at all.
OPTIONAL_FIELDS = ("current_left_a", "current_right_a", "battery_voltage_v", "battery_current_a", "gyro_z_radps")


def log_vector(name: str, value: Any) -> np.ndarray:
    """A read-only float64 1-D copy of ``value``.

    Raises
    ------
    InvalidParameterError
        Not numeric, or not 1-D.
    DataError
        A non-finite value (the message gives the count and the first index).
    """
    arr = real_array(name, value, ndim=1, finite=False)
    bad = ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataError(
            f"{name} must be finite; {int(bad.sum())} non-finite value(s), first at index {i} "
            f"({fmt_number(float(arr[i]), 9)})"
        )
    arr.setflags(write=False)
    return arr


def stream_vector(name: str, value: Any, n: int, clock: str) -> np.ndarray | None:
    """:func:`log_vector` of a stream field that must have ``n`` samples (the length of
    ``clock``); ``None`` stays ``None`` for an optional field.

    Raises
    ------
    InvalidParameterError
        ``None`` for a required field, a wrong length, not numeric or not 1-D.
    DataError
        A non-finite value.
    """
    if value is None:
        if name in OPTIONAL_FIELDS:
            return None
        raise InvalidParameterError(f"{name} is required, got None")
    arr = log_vector(name, value)
    if arr.size != n:
        raise InvalidParameterError(f"{name} must have the length of {clock} ({n}), got {arr.size}")
    return arr


def check_increasing(name: str, t: np.ndarray) -> None:
    """DataError unless ``t`` is non-empty and strictly increasing."""
    if t.size == 0:
        raise DataError(f"{name} is empty; an interaction log needs at least one sample per stream")
    d = np.diff(t)
    bad = d <= 0
    if bad.any():
        i = int(np.argmax(bad)) + 1
        raise DataError(
            f"{name} must be strictly increasing; {int(bad.sum())} step(s) are not, first at index {i} "
            f"(t={fmt_number(float(t[i]), 9)} after t={fmt_number(float(t[i - 1]), 9)})"
        )


def pose_array(value: Any, n: int) -> np.ndarray:
    """A read-only float64 ``(n, 3)`` copy of a pose (x_m, y_m, heading_rad per row).

    Raises
    ------
    InvalidParameterError
        Not numeric, or not of shape ``(n, 3)``.
    DataError
        A non-finite row.
    """
    pose = real_array("pose_xyh", value, finite=False)
    if pose.shape != (n, 3):
        raise InvalidParameterError(f"pose_xyh must have shape ({n}, 3), got {pose.shape!r}")
    bad = ~np.isfinite(pose)
    if bad.any():
        i = int(np.argmax(bad.any(axis=1)))
        raise DataError(f"pose_xyh must be finite; {int(bad.any(axis=1).sum())} row(s) are not, first at index {i}")
    pose.setflags(write=False)
    return pose


def ground_array(value: Any, n: int) -> np.ndarray:
    """A read-only 1-D copy of ``n`` non-empty str ground labels.

    Raises
    ------
    InvalidParameterError
        Wrong shape, or labels that are not strings.
    DataError
        An empty label.
    """
    raw = np.asarray(value)
    if raw.ndim != 1 or raw.size != n:
        raise InvalidParameterError(f"ground must be a 1-D array of {n} labels, got shape {raw.shape!r}")
    if raw.dtype.kind == "O" and all(isinstance(g, str) for g in raw.tolist()):
        raw = raw.astype(str)
    if raw.dtype.kind != "U":
        raise InvalidParameterError(f"ground must hold str labels, got dtype {raw.dtype!r}")
    if n and (np.char.str_len(raw) == 0).any():
        i = int(np.argmax(np.char.str_len(raw) == 0))
        raise DataError(f"ground labels must be non-empty; first empty label at index {i}")
    g = raw.copy()
    g.setflags(write=False)
    return g
