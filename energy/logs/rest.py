"""Standstill: the drive samples where the wheels and the commands are still.

One definition for every part of the library that treats rest apart from driving: the
physics current model's rest level, the estimator's prior, the diagnosis's ``rest_current``
candidate and its localisation, and the bookkeeping of a sensor's rest offset.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["REST_SPEED_MPS", "REST_OMEGA_RADPS", "REST_ACCEL_MPS2", "REST_ALPHA_RADPS2", "at_rest", "rest_samples"]

#: Below this |v| (m/s) a sample does not translate (BorealTC's wheel speeds come in steps
#: of 0.0079 m/s: a still wheel reads exactly 0).
REST_SPEED_MPS = 0.005
#: Below this |omega| (rad/s) a sample does not turn (one encoder step on one side of the
#: Husky is 0.014 rad/s).
REST_OMEGA_RADPS = 0.01
#: Above this |dv/dt| (m/s^2) a still sample is starting or stopping, not resting.
REST_ACCEL_MPS2 = 0.05
#: Above this |d omega/dt| (rad/s^2) a still sample is starting or stopping a turn.
REST_ALPHA_RADPS2 = 0.1


def at_rest(v_mps: Any, omega_radps: Any, accel_mps2: Any = 0.0, alpha_radps2: Any = 0.0) -> np.ndarray:
    """Whether each sample stands still: ``|v| < REST_SPEED_MPS``, ``|omega| < REST_OMEGA_RADPS``
    and (when given) no acceleration, ``|dv/dt| < REST_ACCEL_MPS2``, ``|d omega/dt| < REST_ALPHA_RADPS2``.

    A pivot turn (``v`` near 0, ``omega`` not) is *not* at rest, nor is the instant a start
    from rest or a stop passes through ``v = 0`` (the drive pushes there).

    Parameters
    ----------
    v_mps, omega_radps : array_like
        Speed (m/s) and yaw rate (rad/s) of the samples (commanded or measured), broadcastable.
    accel_mps2, alpha_radps2 : array_like
        Their time derivatives (default 0: not checked).

    Returns
    -------
    numpy.ndarray of bool

    Examples
    --------
    >>> at_rest([0.0, 0.0, 0.3], [0.0, 0.5, 0.0]).tolist()
    [True, False, False]
    """
    v = np.abs(np.asarray(v_mps, dtype=np.float64))
    w = np.abs(np.asarray(omega_radps, dtype=np.float64))
    a = np.abs(np.asarray(accel_mps2, dtype=np.float64))
    al = np.abs(np.asarray(alpha_radps2, dtype=np.float64))
    return (v < REST_SPEED_MPS) & (w < REST_OMEGA_RADPS) & (a < REST_ACCEL_MPS2) & (al < REST_ALPHA_RADPS2)


def rest_samples(log: Any) -> np.ndarray:
    """:func:`at_rest` of an :class:`~energy.logs.InteractionLog`'s drive samples, with ``numpy.gradient``
    of its ``v`` and ``omega`` over its time as the accelerations (a log of 1 sample: its speeds only)."""
    v, w, t = log.v_mps, log.omega_radps, log.time_s
    if len(t) < 2:
        return at_rest(v, w)
    return at_rest(v, w, np.gradient(v, t), np.gradient(w, t))
