"""Yaw-rate slip: the gyro's measured yaw rate against the wheel-derived one, per window of the drive stream."""

from __future__ import annotations

from typing import Any

import numpy as np

from terrawatt_base.checks import check_real, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

from .windows import WindowSpec, sliding_windows, window_starts

__all__ = ["YAW_SLIP_FLOOR_RADPS", "YAW_SLIP_FEATURES", "yaw_slip_features"]

#: Yaw rate (rad/s) below which a window's slip ratio shrinks towards "no slip": the
#: ratio of two small yaw rates is noise, not ground.
YAW_SLIP_FLOOR_RADPS = 0.1
#: Names of the columns of :func:`yaw_slip_features`.
YAW_SLIP_FEATURES = ("skid_fraction", "yaw_deficit_radps")
_SKID_LIMITS = (-1.0, 2.0)


def yaw_slip_features(
    time_s: Any,
    omega_radps: Any,
    gyro_time_s: Any,
    gyro_z_radps: Any,
    spec: WindowSpec,
    starts: Any = None,
    floor_radps: float = YAW_SLIP_FLOOR_RADPS,
) -> np.ndarray:
    """How much of the wheels' yaw rate the robot really turns, per window of a drive stream.

    A skid-steer robot turns by skidding: its wheels' yaw rate ``omega = (vR - vL) / B``
    overstates the body's, by how much depending on the ground. The gyro (averaged over
    each drive sample period, then interpolated onto the drive times) gives the body's
    yaw rate ``g``; over each window of the drive stream:

    - ``skid_fraction = 1 - (sum g*omega + n*f^2) / (sum omega^2 + n*f^2)``: the share of
      the wheels' rotation not realised (0: none lost; 1: the body does not turn), a
      least-squares ratio that shrinks to 0 when ``|omega|`` stays below the floor ``f``
      (straight driving tells nothing about skid), clipped to [-1, 2];
    - ``yaw_deficit_radps = mean(sign(omega) * (omega - g))``: the yaw rate lost (rad/s),
      positive when the body turns less than the wheels say, whichever way it turns.

    Parameters
    ----------
    time_s, omega_radps : array_like, shape (N,)
        Uniformly sampled drive stream: times (s) and wheel-derived (or commanded) yaw rate.
    gyro_time_s, gyro_z_radps : array_like, shape (M,)
        The gyro's yaw rate (rad/s, counter-clockwise positive) on its own clock (the same
        clock as ``time_s``), covering the drive times.
    spec : WindowSpec
        The windows (length and stride in drive samples).
    starts : array_like of int, optional
        First sample of each window; default :func:`window_starts`.
    floor_radps : float
        The yaw rate below which the ratio shrinks to "no slip" (default
        :data:`YAW_SLIP_FLOOR_RADPS`).

    Returns
    -------
    numpy.ndarray, shape (n_windows, 2)
        Columns :data:`YAW_SLIP_FEATURES`.

    Raises
    ------
    InvalidParameterError
        Mismatched shapes, a bad floor.
    DataError
        Non-finite values, fewer than 2 gyro samples, or drive times outside the gyro record.

    Examples
    --------
    >>> t = np.arange(20) / 10.0
    >>> tg = np.arange(200) / 100.0
    >>> spec = WindowSpec.from_seconds(1.0, rate_hz=10.0)
    >>> yaw_slip_features(t, np.full(20, 1.0), tg, np.full(200, 0.6), spec).round(3).tolist()
    [[0.396, 0.4], [0.396, 0.4]]
    """
    floor = check_real("floor_radps", floor_radps, low=0.0, low_inclusive=False)
    t = real_array("time_s", time_s, ndim=1)
    w = real_array("omega_radps", omega_radps, ndim=1)
    tg = real_array("gyro_time_s", gyro_time_s, ndim=1)
    g = real_array("gyro_z_radps", gyro_z_radps, ndim=1)
    if w.shape != t.shape or g.shape != tg.shape:
        raise InvalidParameterError(
            f"time_s/omega_radps and gyro_time_s/gyro_z_radps must be pairs of one length, got "
            f"{t.shape!r}/{w.shape!r} and {tg.shape!r}/{g.shape!r}"
        )
    if tg.size < 2:
        raise DataError(f"yaw-rate slip needs at least 2 gyro samples, got {tg.size}")
    if t[0] < tg[0] - 1e-9 or t[-1] > tg[-1] + 1e-9:
        raise DataError(
            f"the drive times [{t[0]:.3f}, {t[-1]:.3f}] s reach outside the gyro record [{tg[0]:.3f}, {tg[-1]:.3f}] s"
        )
    # the gyro averaged over one drive period (it is sampled much faster and vibrates)
    per_drive = max(1, int(round(spec.rate_hz ** -1 / float(np.median(np.diff(tg))))))
    if per_drive > 1:
        kernel = np.ones(per_drive) / per_drive
        g = np.convolve(np.pad(g, (per_drive // 2, per_drive - 1 - per_drive // 2), mode="edge"), kernel, mode="valid")
    g_drive = np.interp(t, tg, g)
    if starts is None:
        starts = window_starts(t.size, spec)
    ww = sliding_windows(w, spec, np.asarray(starts))
    gw = sliding_windows(g_drive, spec, np.asarray(starts))
    n = ww.shape[1]
    ratio = (np.sum(gw * ww, axis=1) + n * floor**2) / (np.sum(ww**2, axis=1) + n * floor**2)
    skid = np.clip(1.0 - ratio, *_SKID_LIMITS)
    deficit = np.mean(np.sign(ww) * (ww - gw), axis=1)
    return np.column_stack([skid, deficit])
