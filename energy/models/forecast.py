"""A current forecast with its interval: the mean and two kinds of spread, and what they mean for charge.

A model's :meth:`~energy.models.CurrentModel.predict_distribution` returns a
:class:`CurrentForecast`: per drive sample and side the mean current and two standard
deviations that differ in how they add up over time:

- ``run_sd_a``: the part of the error **shared by a whole run on one ground** — what the
  model does not know about this ground and how one run differs from another (a softer
  ground today, a heavier payload, another tyre pressure). It is fully correlated along the
  run and between the two sides: over a stretch it adds up linearly, so it does not
  average out with distance.
- ``sample_sd_a``: the part independent from sample to sample (sensor noise, a bump): over
  a stretch it adds up in quadrature and averages out.

The charge of a stretch then has mean ``∫ mean dt`` and scale
``sqrt((∫ run_sd dt)² + Σ (sample_sd Δt)²)`` (per side; for both sides the run parts add
linearly). Its shape is a **Student-t with** ``dof`` **degrees of freedom**: on a ground the
model never drove, the number of grounds the new-ground spread was learned from
(:attr:`~energy.models.uncertainty.IntervalModel.new_ground_dof`); on a ground it drove, the
number of runs its run spread was read from
(:meth:`~energy.models.uncertainty.IntervalModel.run_dof`): a spread estimated from a few
grounds or runs is itself uncertain, and its tails are heavier than a Gaussian's (``dof = inf``
is the Gaussian: a model file from before the counts were recorded). A route crossing several grounds is priced the same way per ground, the grounds
being independent of each other (see :func:`combine_ground_sds`).

A model without an interval returns zero spreads (``has_interval`` False).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import norm
from scipy.stats import t as student_t

from terrawatt_base.checks import check_real
from terrawatt_base.errors import InvalidParameterError

from ..power import trapezoid as _trapezoid

__all__ = ["CurrentForecast", "ChargeForecast", "predictive_quantile", "central_level",
           "check_dof", "combine_ground_sds"]


def check_dof(dof: float, name: str = "dof") -> float:
    """A predictive's degrees of freedom: a number > 0, ``math.inf`` for the Gaussian."""
    if isinstance(dof, (int, float, np.floating)) and not isinstance(dof, bool) and float(dof) == math.inf:
        return math.inf
    return check_real(name, dof, low=0.0, low_inclusive=False)


def predictive_quantile(q: float, dof: float = math.inf) -> float:
    """The ``q`` quantile of the standardised predictive: Student-t with ``dof`` degrees of freedom (inf: Gaussian).

    >>> round(predictive_quantile(0.9), 4), round(predictive_quantile(0.9, 3.0), 4)
    (1.2816, 1.6377)
    """
    q = check_real("q", q, low=0.0, high=1.0, low_inclusive=False, high_inclusive=False)
    dof = check_dof(dof)
    return float(norm.ppf(q)) if math.isinf(dof) else float(student_t.ppf(q, dof))


def central_level(z: float | np.ndarray, dof: float | np.ndarray = math.inf) -> np.ndarray:
    """The least central interval level that holds a standardised error ``z`` (``2 F(|z|) - 1``; NaN stays NaN).

    A forecast is covered at level ``L`` when this is ``<= L``: one test for Gaussian and
    Student-t forecasts alike.
    """
    z = np.abs(np.asarray(z, dtype=np.float64))
    dof = np.broadcast_to(np.asarray(dof, dtype=np.float64), z.shape)
    gauss = np.isinf(dof)
    out = np.where(gauss, 2.0 * norm.cdf(z) - 1.0, 2.0 * student_t.cdf(z, np.where(gauss, 1.0, dof)) - 1.0)
    return np.where(np.isnan(z), np.nan, out)


def combine_ground_sds(sd_by_ground: Sequence[float]) -> float:
    """Standard deviation of a sum of per-ground totals, the grounds independent: root of the sum of squares.

    Within one ground the per-edge run-level spreads add linearly (one run on one ground
    shares its error); the per-ground sums are then combined here.
    """
    arr = np.asarray(list(sd_by_ground), dtype=np.float64)
    return float(math.sqrt(float(np.sum(arr**2)))) if arr.size else 0.0


@dataclass(frozen=True)
class ChargeForecast:
    """Forecast of a charge (A s) per side and for both sides together: a location, a scale and a tail.

    Attributes
    ----------
    mean_as : ndarray, shape (2,)
        ``[left, right]`` mean charge (A s).
    sd_as : ndarray, shape (2,)
        Their standard deviations (A s).
    total_mean_as, total_sd_as : float
        Both sides together (the run-level parts of the two sides fully correlated).
    dof : float
        Degrees of freedom of the Student-t the scales belong to (``inf``: Gaussian; see the
        module docstring).
    """

    mean_as: np.ndarray
    sd_as: np.ndarray
    total_mean_as: float
    total_sd_as: float
    dof: float = math.inf

    def interval(self, level: float) -> tuple[float, float]:
        """Central ``level`` interval of the two sides' total charge (A s), e.g. ``level=0.8``: P10-P90."""
        lv = check_real("level", level, low=0.0, high=1.0, low_inclusive=False, high_inclusive=False)
        z = predictive_quantile(0.5 + lv / 2.0, self.dof)
        return self.total_mean_as - z * self.total_sd_as, self.total_mean_as + z * self.total_sd_as

    def quantile(self, q: float) -> float:
        """The ``q`` quantile of the two sides' total charge (A s)."""
        return self.total_mean_as + predictive_quantile(q, self.dof) * self.total_sd_as


@dataclass(frozen=True)
class CurrentForecast:
    """Per drive sample and side: mean current and the run-level and per-sample standard deviations (A).

    Parameters
    ----------
    time_s : ndarray, shape (N,)
        The log's drive timestamps.
    mean_a, run_sd_a, sample_sd_a : ndarray, shape (N, 2)
        ``[left, right]``: the mean (what ``predict`` returns), the spread shared by the whole
        run on one ground and the spread independent per sample (both >= 0).
    dof : float
        Degrees of freedom of the forecast's Student-t (``inf``, the default: Gaussian; a
        model gives a finite one on a ground it never drove, see the module docstring).

    Raises
    ------
    InvalidParameterError
        Shapes that differ, non-finite values, negative spreads, ``dof`` not > 0.
    """

    time_s: np.ndarray
    mean_a: np.ndarray
    run_sd_a: np.ndarray
    sample_sd_a: np.ndarray
    dof: float = math.inf

    def __post_init__(self) -> None:
        t = np.asarray(self.time_s, dtype=np.float64)
        arrays = [np.asarray(getattr(self, n), dtype=np.float64) for n in ("mean_a", "run_sd_a", "sample_sd_a")]
        if t.ndim != 1 or any(a.shape != (t.size, 2) for a in arrays):
            raise InvalidParameterError(
                f"CurrentForecast needs time_s of shape (N,) and (N, 2) arrays; got {t.shape!r} and "
                f"{[a.shape for a in arrays]!r}"
            )
        if not (np.all(np.isfinite(t)) and all(np.all(np.isfinite(a)) for a in arrays)):
            raise InvalidParameterError("CurrentForecast values must be finite")
        if np.any(arrays[1] < 0) or np.any(arrays[2] < 0):
            raise InvalidParameterError("CurrentForecast spreads must be >= 0")
        for name, a in zip(("mean_a", "run_sd_a", "sample_sd_a"), arrays):
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        t.setflags(write=False)
        object.__setattr__(self, "time_s", t)
        object.__setattr__(self, "dof", check_dof(self.dof, "CurrentForecast.dof"))

    @classmethod
    def point(cls, time_s: np.ndarray, mean_a: np.ndarray) -> CurrentForecast:
        """A forecast without an interval (both spreads zero)."""
        zeros = np.zeros_like(np.asarray(mean_a, dtype=np.float64))
        return cls(time_s, mean_a, zeros, zeros)

    @property
    def has_interval(self) -> bool:
        """Whether any spread is non-zero."""
        return bool(np.any(self.run_sd_a > 0) or np.any(self.sample_sd_a > 0))

    @property
    def sd_a(self) -> np.ndarray:
        """Total per-sample standard deviation ``sqrt(run_sd² + sample_sd²)`` (A), shape (N, 2)."""
        return np.sqrt(self.run_sd_a**2 + self.sample_sd_a**2)

    def charge(self, mask: np.ndarray | None = None) -> ChargeForecast:
        """The forecast of the charge over the log (or the samples where ``mask`` is True), with this forecast's ``dof``.

        The run-level spread is integrated like the mean (fully correlated in time and between
        sides); the per-sample spread in quadrature with each sample's time step.
        """
        t, mean, run, white = self.time_s, self.mean_a, self.run_sd_a, self.sample_sd_a
        if mask is not None:
            m = np.asarray(mask, dtype=bool)
            if m.shape != t.shape:
                raise InvalidParameterError(f"mask must have shape {t.shape!r}, got {m.shape!r}")
            t, mean, run, white = t[m], mean[m], run[m], white[m]
        if t.size < 2:
            zero = np.zeros(2)
            return ChargeForecast(zero, zero.copy(), 0.0, 0.0, self.dof)
        dt = np.gradient(t)
        q_mean = _trapezoid(mean, t, axis=0)
        q_run = _trapezoid(run, t, axis=0)
        q_white = np.sqrt(np.sum((white * dt[:, None]) ** 2, axis=0))
        sd = np.sqrt(q_run**2 + q_white**2)
        total_sd = math.sqrt(float(q_run.sum()) ** 2 + float(np.sum(q_white**2)))
        return ChargeForecast(q_mean, sd, float(q_mean.sum()), total_sd, self.dof)

    def quantile_a(self, q: float) -> np.ndarray:
        """Per-sample ``q`` quantile of the current (A), shape (N, 2)."""
        return self.mean_a + predictive_quantile(q, self.dof) * self.sd_a
