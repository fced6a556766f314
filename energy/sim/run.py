"""The result of a truth simulation: the synthetic log with the noise-free truth behind it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from terrawatt_base.errors import InvalidParameterError

from ..logs import InteractionLog
from ..power import PowerBreakdown

__all__ = ["TruthRun"]


@dataclass(frozen=True, eq=False)
class TruthRun:
    """A synthesised log with the noise-free truth behind it.

    Attributes
    ----------
    log : InteractionLog
        What a robot would have recorded (commands, measured currents, acceleration).
    breakdown : PowerBreakdown
        The physics model's output for the tracked motion (battery power, signed motor
        currents, per-effect components).
    actual_v_mps, actual_omega_radps : numpy.ndarray, shape (N,)
        Tracked (lagged) speed and yaw rate.
    accel_mps2, alpha_radps2 : numpy.ndarray, shape (N,)
        Their time derivatives as fed to the physics model.
    slope_rad : numpy.ndarray, shape (N,)
        Pitch along the heading (positive uphill).
    resistance_factor : numpy.ndarray, shape (N,)
        Ground-variation factor on the resistance coefficients (1 without variation).
    clean_current_a : numpy.ndarray, shape (N, 2)
        ``[left, right]`` current as the sensor would read it without noise, outliers and
        quantisation (gains, idle and clipping applied), A.
    """

    log: InteractionLog
    breakdown: PowerBreakdown
    actual_v_mps: np.ndarray
    actual_omega_radps: np.ndarray
    accel_mps2: np.ndarray
    alpha_radps2: np.ndarray
    slope_rad: np.ndarray
    resistance_factor: np.ndarray
    clean_current_a: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.log)
        for name in ("actual_v_mps", "actual_omega_radps", "accel_mps2", "alpha_radps2", "slope_rad",
                     "resistance_factor", "clean_current_a"):
            arr = np.array(getattr(self, name), dtype=np.float64)
            expected = (n, 2) if name == "clean_current_a" else (n,)
            if arr.shape != expected:
                raise InvalidParameterError(f"TruthRun.{name} must have shape {expected!r}, got {arr.shape!r}")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if self.breakdown.n_samples != n:
            raise InvalidParameterError(
                f"TruthRun.breakdown must have {n} samples like the log, got {self.breakdown.n_samples}"
            )


# ============================================================================= simulator
