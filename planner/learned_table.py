"""LearnedModelTable: one current model's flat-ground energy tables, and the checked prediction behind them."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from energy import InteractionLog
from energy.models.forecast import check_dof
from terrawatt_base.checks import check_real
from terrawatt_base.errors import InvalidParameterError

__all__ = ["TableProbe", "LearnedModelTable", "predict_currents", "predict_current_spread", "model_gives_interval",
           "increasing_grid", "DEFAULT_TABLE_SPEEDS_MPS", "DEFAULT_TABLE_OMEGAS_RADPS"]

#: Default speeds of the flat-ground tables (m/s).
DEFAULT_TABLE_SPEEDS_MPS: tuple[float, ...] = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0)
#: Default pivot rates of the turn tables (rad/s).
DEFAULT_TABLE_OMEGAS_RADPS: tuple[float, ...] = (0.25, 0.5, 0.75, 1.0, 1.5)


def increasing_grid(name: str, values: Sequence[float]) -> np.ndarray:
    """``values`` as a non-empty, strictly increasing float array of numbers > 0 (a table grid).

    Raises
    ------
    InvalidParameterError
        Anything else; the message names ``name``.
    """
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{name} must be a sequence of numbers, got {values!r:.80}") from exc
    if arr.ndim != 1 or arr.size < 1 or not np.all(np.isfinite(arr)) or np.any(arr <= 0) or np.any(np.diff(arr) <= 0):
        raise InvalidParameterError(f"{name} must be a non-empty, strictly increasing sequence of numbers > 0, got {values!r}")
    return arr


def predict_currents(model: Any, log: InteractionLog, label: str) -> np.ndarray:
    """``model.predict(log)`` checked: finite ``(len(log), 2)`` left/right currents (A).

    Every place the planner asks a current model for currents goes through here, so a model
    with another feature or output layout fails with a message naming it rather than with a
    numpy error or, worse, silently (an ``(N, 3)`` output is not cut to two columns).

    Raises
    ------
    InvalidParameterError
        The prediction is not a finite ``(len(log), 2)`` array; ``label`` names the model.
    """
    try:
        pred = np.asarray(model.predict(log), dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{label} could not predict currents for a {len(log)}-sample log: {exc}") from exc
    if pred.shape != (len(log), 2) or not np.all(np.isfinite(pred)):
        what = "non-finite values" if pred.shape == (len(log), 2) else f"shape {pred.shape!r}"
        raise InvalidParameterError(
            f"{label} must predict finite (N, 2) left/right currents for a log of N={len(log)} samples, got {what}"
        )
    return pred


def model_gives_interval(model: Any) -> bool:
    """Whether ``model`` has a :meth:`~energy.CurrentModel.predict_distribution` with spreads (``gives_interval``)."""
    return bool(getattr(model, "gives_interval", False)) and callable(getattr(model, "predict_distribution", None))


def predict_current_spread(model: Any, log: InteractionLog, label: str) -> tuple[np.ndarray, np.ndarray, float]:
    """``model.predict_distribution(log)`` checked: the mean and the run-level standard deviation, each ``(N, 2)`` (A),
    and the forecast's degrees of freedom.

    Only the run-level spread (``run_sd_a``) is returned: it is the part shared by a whole
    run on one ground, so it does not average out over a route; the per-sample spread does
    (it shrinks as one over the square root of the samples) and is left out of planning.
    The degrees of freedom (``dof``: ``inf`` for a Gaussian forecast, finite for the
    Student-t of a ground the model never drove; a forecast without one is Gaussian) say
    which distribution the spread is the scale of.

    Raises
    ------
    InvalidParameterError
        The forecast is not finite ``(len(log), 2)`` arrays, or its ``dof`` is not > 0;
        ``label`` names the model.
    """
    try:
        forecast = model.predict_distribution(log)
        mean = np.asarray(forecast.mean_a, dtype=np.float64)
        run_sd = np.asarray(forecast.run_sd_a, dtype=np.float64)
        dof = check_dof(getattr(forecast, "dof", math.inf), f"{label}'s forecast dof")
    except (TypeError, ValueError, AttributeError) as exc:
        raise InvalidParameterError(f"{label} could not forecast currents for a {len(log)}-sample log: {exc}") from exc
    shape = (len(log), 2)
    if mean.shape != shape or run_sd.shape != shape or not (np.all(np.isfinite(mean)) and np.all(np.isfinite(run_sd))):
        raise InvalidParameterError(
            f"{label} must forecast finite (N, 2) mean and run-level spread for a log of N={len(log)} samples, got "
            f"shapes {mean.shape!r} and {run_sd.shape!r}"
        )
    return mean, run_sd, dof


@dataclass(frozen=True)
class TableProbe:
    """How a current model is asked for its flat-ground tables: a synthetic log of held levels, each averaged.

    The log holds each speed (straight) and each pivot rate (turning in place) for ``hold_s``
    at ``rate_hz``; the first ``settle_s`` of each level is left out of its average.

    Parameters
    ----------
    speeds_mps, omegas_radps : sequence of float
        The table grids (> 0, strictly increasing).
    hold_s, settle_s : float
        Hold time of each level and the settling time left out of its average
        (0 <= settle_s < hold_s).
    rate_hz : float
        Sample rate of the synthetic log (Hz, > 0).

    Raises
    ------
    InvalidParameterError
        Bad grids or times (the message names the parameter).

    Examples
    --------
    >>> TableProbe(speeds_mps=(0.25, 0.5, 1.0)).speeds_mps
    array([0.25, 0.5 , 1.  ])
    """

    speeds_mps: Any = DEFAULT_TABLE_SPEEDS_MPS
    omegas_radps: Any = DEFAULT_TABLE_OMEGAS_RADPS
    hold_s: float = 2.0
    settle_s: float = 0.5
    rate_hz: float = 100.0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "speeds_mps", increasing_grid("speeds_mps", self.speeds_mps))
        set_(self, "omegas_radps", increasing_grid("omegas_radps", self.omegas_radps))
        hold = check_real("hold_s", self.hold_s, low=0.0, low_inclusive=False)
        set_(self, "hold_s", hold)
        set_(self, "rate_hz", check_real("rate_hz", self.rate_hz, low=0.0, low_inclusive=False))
        set_(self, "settle_s", check_real("settle_s", self.settle_s, low=0.0, high=hold, high_inclusive=False))
        for grid in (self.speeds_mps, self.omegas_radps):
            grid.setflags(write=False)


@dataclass(frozen=True, eq=False)
class LearnedModelTable:
    """Flat-ground energy tables of one current model (see :mod:`planner.learned_cost`).

    Attributes
    ----------
    model_id : int
        Id of the model in the registry.
    speeds_mps : ndarray, shape (S,)
        Speed grid (m/s).
    energy_per_metre_j : ndarray, shape (S,)
        Battery energy per metre of straight flat driving, electronics included (J/m).
    omegas_radps : ndarray, shape (W,)
        Turn-rate grid (rad/s).
    turn_energy_per_rad_j : ndarray, shape (W,)
        Battery energy per radian of turning in place, electronics included (J/rad).
    mean_current_a : ndarray, shape (S + W, 2)
        The settled mean predicted ``[left, right]`` currents behind the tables (A).
    build_time_s : float
        Seconds spent building the table (prediction included).
    energy_per_metre_sd_j, turn_energy_per_rad_sd_j : ndarray or None
        Run-level standard deviations of the two tables (J/m, J/rad; shapes of the means),
        from the model's predictive distribution; None for a model without an interval.
    dof : float
        Degrees of freedom of the predictive the spreads are the scale of: ``inf`` (the
        default) for a Gaussian, finite for a Student-t (as many as grounds on a ground the model
        never drove, as runs on one it drove: :attr:`energy.models.forecast.CurrentForecast.dof`).
    """

    model_id: int
    speeds_mps: np.ndarray
    energy_per_metre_j: np.ndarray
    omegas_radps: np.ndarray
    turn_energy_per_rad_j: np.ndarray
    mean_current_a: np.ndarray
    build_time_s: float
    energy_per_metre_sd_j: np.ndarray | None = None
    turn_energy_per_rad_sd_j: np.ndarray | None = None
    dof: float = math.inf

    def __post_init__(self) -> None:
        object.__setattr__(self, "dof", check_dof(self.dof, "LearnedModelTable.dof"))
        if (self.energy_per_metre_sd_j is None) != (self.turn_energy_per_rad_sd_j is None):
            raise InvalidParameterError("LearnedModelTable: the two spread tables go together (both or neither)")
        names = ["speeds_mps", "energy_per_metre_j", "omegas_radps", "turn_energy_per_rad_j", "mean_current_a"]
        if self.energy_per_metre_sd_j is not None:
            names += ["energy_per_metre_sd_j", "turn_energy_per_rad_sd_j"]
        for name in names:
            arr = np.array(getattr(self, name), dtype=np.float64)
            if not np.all(np.isfinite(arr)):
                raise InvalidParameterError(f"LearnedModelTable.{name} must be finite, got {arr!r}")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if self.energy_per_metre_j.shape != self.speeds_mps.shape:
            raise InvalidParameterError("LearnedModelTable: energy_per_metre_j must match speeds_mps")
        if self.turn_energy_per_rad_j.shape != self.omegas_radps.shape:
            raise InvalidParameterError("LearnedModelTable: turn_energy_per_rad_j must match omegas_radps")
        if self.energy_per_metre_sd_j is not None and (
                self.energy_per_metre_sd_j.shape != self.speeds_mps.shape
                or self.turn_energy_per_rad_sd_j.shape != self.omegas_radps.shape
                or np.any(self.energy_per_metre_sd_j < 0) or np.any(self.turn_energy_per_rad_sd_j < 0)):
            raise InvalidParameterError("LearnedModelTable: the spread tables must match their grids and be >= 0")

    @property
    def has_interval(self) -> bool:
        """Whether the table carries spreads (some > 0)."""
        return self.energy_per_metre_sd_j is not None and bool(
            np.any(self.energy_per_metre_sd_j > 0) or np.any(self.turn_energy_per_rad_sd_j > 0))

    def energy_per_metre_sd_at(self, speed_mps: float) -> float:
        """Run-level standard deviation of the flat-ground J/m at ``speed_mps`` (0 without an interval)."""
        if self.energy_per_metre_sd_j is None:
            return 0.0
        return float(np.interp(speed_mps, self.speeds_mps, self.energy_per_metre_sd_j))

    def turn_energy_per_rad_sd_at(self, omega_radps: float) -> float:
        """Run-level standard deviation of the J/rad at ``omega_radps`` (0 without an interval)."""
        if self.turn_energy_per_rad_sd_j is None:
            return 0.0
        return float(np.interp(omega_radps, self.omegas_radps, self.turn_energy_per_rad_sd_j))

    def energy_per_metre_at(self, speed_mps: float) -> float:
        """Flat-ground J/m at ``speed_mps``, linearly interpolated (constant beyond the grid)."""
        return float(np.interp(speed_mps, self.speeds_mps, self.energy_per_metre_j))

    def turn_energy_per_rad_at(self, omega_radps: float) -> float:
        """J/rad of turning at ``omega_radps``, linearly interpolated (constant beyond the grid)."""
        return float(np.interp(omega_radps, self.omegas_radps, self.turn_energy_per_rad_j))
