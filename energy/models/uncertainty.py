"""How wrong a current model may be: run-to-run and new-ground spreads, fitted on residuals the model did not see.

The error of a current model on a run is split in two (see :mod:`energy.models.forecast`):

- a **run-level** part, shared by every sample of the run (the ground is softer today, the
  payload heavier, the ground is one the model never drove). It is written in the *regime
  basis* of the motion, per side ``phi(t) = [|I(t)|, 1, m, m * outer]`` while moving (zero
  standing still) with ``I`` the predicted current, ``m = tanh(|omega| / turn_scale)``
  (0 straight, 1 turning) and ``outer`` 1 on the outer side of a turn: a gain on the
  predicted current plus the terms in which a nominal physics model is affine in its
  ground parameters (rolling resistance adds a constant current while moving, lateral
  friction one while turning, mostly on the outer side). One gain per side — the baseline
  every update is compared with — is the special case ``[g - 1, 0, 0, 0]``. (Measured on
  the shared logs against a purely additive basis ``[1, |v|, m, m * outer]`` and a purely
  relative one, ``|I|`` times it: the additive one forecast snow best but a new ground's
  p90 worse than the gain, the relative one never worse than the gain but snow worst; this
  one nests the gain and forecast flooring best.) A run's error is ``phi(t) . beta`` with
  ``beta`` drawn from ``N(0, S)``: ``S`` is the **run covariance** of the ground (how runs of a
  known ground differ from the model, fitted per ground where it has runs enough, else
  pooled) plus, for a ground the model never drove, the **new-ground covariance** (how far
  a ground left out of the fit lies from a model fitted on the others). The spread
  ``sqrt(phi S phi)`` is heteroscedastic in the current level, turn rate and ground. A run
  covariance from few runs is shrunk to its diagonal, which alone forecasts a charge wider or
  narrower than any run was off (the columns trade off within a run): its scale is read where
  it is used, from the whole-run residual charges it was fitted on
  (:meth:`IntervalModel.charge_scale`). The new-ground covariance keeps the scale of its
  diagonal: two to five grounds cannot tell it (measured: docs/results.md).
- a **per-sample** part (sensor noise, bumps): a standard deviation per side and regime
  (rest, straight, turning) with an integrated correlation time ``correlation_s``; over a
  stretch it averages out.

:class:`IntervalModel.fit` estimates all of it from *out-of-fold* residuals (each training
run predicted by ensemble members that never saw it — the cross-validation ensemble of
:class:`~energy.models.VibrationCurrentEstimator`) and from leave-one-ground-out residuals
of the physics prior (the new-ground covariance needs two grounds or more). The same
quantities are the prior of the Bayesian few-shot update
(:class:`~energy.models.AdaptedCurrentModel`, ``method="bayes"``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_bool, check_int, check_real

from ..logs import InteractionLog, rest_samples
from ..power import trapezoid as _trapezoid

__all__ = ["REGIME_COLUMNS", "IntervalModel", "regime_design", "run_coefficients"]

#: Columns of the regime basis (per side).
REGIME_COLUMNS = ("gain - 1", "offset A", "turning A", "outer turning A")
#: Ridge penalty of a run's regime coefficients, in seconds of data showing no residual: a
#: regime the run never drove keeps a coefficient near 0 instead of an arbitrary one.
RUN_RIDGE_S = 2.0
#: Default ``turn_scale_radps`` of the regime basis.
DEFAULT_TURN_SCALE_RADPS = 0.3
#: Regimes of the per-sample spread.
SAMPLE_REGIMES = ("rest", "straight", "turning")
_POOLED = "*"
_MIN_GROUND_RUNS = 3  # a ground's own run covariance needs this many runs, else the pooled one
#: Least number of training runs the carry of a run's offset along it (:attr:`IntervalModel.run_carry`) is learned from.
MIN_CARRY_RUNS = 3
_MAX_LAGS = 50  # lags (drive samples) of the per-sample residual's autocorrelation (~8 s at 6.5 Hz)


#: Largest variance a run-level regime coefficient may have in a saved model: a gain sd of 1000
#: or an offset sd of 1000 A is already no forecast; a file beyond it is corrupt or hostile.
MAX_RUN_VARIANCE = 1e6
#: Largest per-sample spread of a saved model (A).
MAX_SAMPLE_SD_A = 1e3


def check_covariances(name: str, cov: np.ndarray, max_variance: float) -> None:
    """Raise ValueError unless every ``cov[s]`` (per side) is a symmetric positive semi-definite matrix whose
    variances are at most ``max_variance``: negative, negated or ×1e30 variances mean nothing as a spread (a
    negated one *narrows* the interval it should widen; a huge one prints negative energies)."""
    for s, c in enumerate(cov):
        scale = max(float(np.max(np.abs(c))), 1e-300)
        if not np.allclose(c, c.T, rtol=1e-9, atol=1e-12 * scale):
            raise ValueError(f"{name}[{s}] is not symmetric: not a covariance")
        if np.any(np.diag(c) < 0) or float(np.linalg.eigvalsh(c).min()) < -1e-9 * scale:
            raise ValueError(f"{name}[{s}] has a negative variance (it is not positive semi-definite): a spread cannot "
                             "be negative")
        if float(np.max(np.diag(c))) > max_variance:
            raise ValueError(f"{name}[{s}] has a variance of {float(np.max(np.diag(c))):.3g}, beyond any plausible "
                             f"spread (at most {max_variance:g})")


def regime_design(log: InteractionLog, side: int, turn_scale_radps: float, level_a: np.ndarray) -> np.ndarray:
    """``[|I|, 1, m, m * outer]`` per moving sample for one side (0 left, 1 right), zero at rest; shape (N, 4).

    ``level_a`` is the model's predicted current of that side (N,). Standing still is the
    model's rest level (:func:`energy.logs.rest_samples`), not a regime of driving: its
    spread is the per-sample one.
    """
    m = np.tanh(np.abs(log.omega_radps) / turn_scale_radps)
    sign = -1.0 if side == 0 else 1.0
    outer = (sign * log.omega_radps > 0).astype(np.float64)
    moving = (~rest_samples(log)).astype(np.float64)
    level = np.abs(np.asarray(level_a, dtype=np.float64))
    return np.column_stack([level, np.ones(len(log)), m, m * outer]) * moving[:, None]


def sample_spans_s(log: InteractionLog) -> np.ndarray:
    """The time each drive sample stands for (s): the central difference of its neighbours' times, a full step at the ends.

    Not the trapezoid weights of :func:`energy.diagnosis.gap.sample_weights_s` (half a step at
    the ends): the fits of the interval and the update weigh every sample by the span it stands for.
    """
    return np.gradient(log.time_s) if len(log) > 1 else np.ones(len(log))


def run_coefficients(log: InteractionLog, residual_a: np.ndarray, level_a: np.ndarray, turn_scale_radps: float,
                     ridge_s: float = RUN_RIDGE_S) -> np.ndarray:
    """Per side, the regime coefficients of a residual current (time-weighted ridge fit), shape (2, 4).

    ``level_a`` (N, 2) are the predictions the residual is of (the gain column's scale); the
    gain's penalty is on the scale of the mean squared level, the others' in A².
    """
    w = sample_spans_s(log)
    out = np.zeros((2, len(REGIME_COLUMNS)))
    for k in range(2):
        x = regime_design(log, k, turn_scale_radps, level_a[:, k])
        scale = np.ones(x.shape[1])
        scale[0] = max(float(np.average(level_a[:, k] ** 2, weights=w)), 0.25)
        a = (x * w[:, None]).T @ x + ridge_s * np.diag(scale)
        out[k] = np.linalg.solve(a, (x * w[:, None]).T @ residual_a[:, k])
    return out


def _regime_of(log: InteractionLog, turn_scale_radps: float) -> np.ndarray:
    """0 rest, 1 straight, 2 turning per sample."""
    reg = np.where(np.tanh(np.abs(log.omega_radps) / turn_scale_radps) > 0.5, 2, 1)
    reg[rest_samples(log)] = 0
    return reg


def _second_moment(rows: np.ndarray) -> np.ndarray:
    """Mean of ``b b^T`` over the first axis, per side: rows (n, 2, k) -> (2, k, k)."""
    return np.einsum("nsi,nsj->sij", rows, rows) / max(rows.shape[0], 1)


def _diagonal(cov: np.ndarray) -> np.ndarray:
    """Per side, the covariance with its off-diagonal terms dropped."""
    return np.stack([np.diag(np.diag(c)) for c in cov])


def _shrunk(cov: np.ndarray, n: int) -> np.ndarray:
    """Covariance estimated from ``n`` runs, shrunk towards its diagonal (fully at 4 runs, not at all from 20)."""
    keep = min(max((n - _MIN_GROUND_RUNS) / 17.0, 0.0), 1.0)
    return keep * cov + (1.0 - keep) * _diagonal(cov)


def _integrated_time(acov: np.ndarray, dt: float) -> float:
    """Integrated correlation time ``dt (1 + 2 sum rho_k)`` of a pooled autocovariance, summed until rho turns negative."""
    if acov[0] <= 0:
        return dt
    rho = acov[1:] / acov[0]
    stop = int(np.argmax(rho <= 0)) if np.any(rho <= 0) else rho.size
    return dt * (1.0 + 2.0 * float(np.sum(rho[:stop])))


def _quadratic_sd(x: np.ndarray, cov: np.ndarray) -> np.ndarray:
    return np.sqrt(np.maximum(np.einsum("ni,ij,nj->n", x, cov, x), 0.0))


@dataclass(frozen=True)
class IntervalModel:
    """The fitted spreads of a current model (see the module docstring).

    Attributes
    ----------
    turn_scale_radps : float
        Of the regime basis.
    run_cov : dict of str to ndarray (2, 4, 4)
        Per ground (training label, lower case) and pooled (``"*"``): the second moment of
        the run-level regime coefficients of out-of-fold residuals, per side, scaled so that it
        forecasts those runs' residual charges (:meth:`charge_scale`; a model file from before
        holds it unscaled).
    new_ground_cov : ndarray (2, 4, 4) or None
        Added for a ground the model never drove; ``None`` when the training logs held one
        ground only (nothing to learn it from: such a forecast carries the run spread only).
    sample_sd_a : ndarray (2, 3)
        Per side, the per-sample spread at rest, straight and turning (A).
    correlation_s : float
        Integrated correlation time of the per-sample residual (s).
    cross_validated : bool
        Whether the residuals were out-of-fold (False: in-sample, fewer than 2 training runs;
        such spreads are too narrow).
    n_runs : int
        Training runs the spreads were fitted on.
    n_grounds : int
        Grounds the new-ground covariance was learned from (0: none, or a file from before
        it was recorded).
    run_counts : dict of str to int or None
        Per key of :attr:`run_cov`, the training runs it was fitted and scaled on (the pooled key:
        all of them); ``None`` in a model file from before they were recorded.
    run_carry : float or None
        How much of a run's own offset carries along it: the correlation, over the training
        runs, of the run-level parts of the residual charges of each run's two halves (the
        per-sample noise's share taken out of their variances; in [0, 1]). 1 is an offset
        constant along the run, 0 one that the first half says nothing of the second with.
        ``None`` where it could not be learned (fewer than :data:`MIN_CARRY_RUNS` runs, no
        run-level part left after the noise's) or in a file from before it was recorded.
    """

    turn_scale_radps: float
    run_cov: dict[str, np.ndarray]
    new_ground_cov: np.ndarray | None
    sample_sd_a: np.ndarray
    correlation_s: float
    cross_validated: bool
    n_runs: int
    n_grounds: int = 0
    run_carry: float | None = None
    run_counts: dict[str, int] | None = None

    @property
    def new_ground_dof(self) -> float:
        """Degrees of freedom of a forecast on a ground the model never drove.

        The new-ground covariance is the second moment of ``n_grounds`` left-out grounds'
        offsets, so the variance of a new ground is itself a ``n_grounds``-degree estimate
        and the forecast is a Student-t with as many degrees of freedom (heavy-tailed with two
        or three grounds, near Gaussian with many). ``inf`` (Gaussian) without a new-ground
        covariance or a recorded count.
        """
        return float(self.n_grounds) if self.new_ground_cov is not None and self.n_grounds > 0 else math.inf

    def run_dof(self, ground: str | None) -> float:
        """Degrees of freedom of a forecast on ``ground``, a ground the model drove.

        The scale of the run covariance is read from the residual charges of the runs it was fitted
        on (:meth:`charge_scale`), so a run's spread is itself an estimate from as many runs and the
        forecast a Student-t with as many degrees of freedom: heavy-tailed where a ground taught it
        with a handful of runs, near Gaussian with many. ``inf`` (Gaussian) in a model file from
        before the counts were recorded.
        """
        if self.run_counts is None:
            return math.inf
        key = str(ground).lower() if ground is not None else _POOLED
        return float(self.run_counts.get(key if key in self.run_cov else _POOLED, self.n_runs))

    # ------------------------------------------------------------------ fit
    @classmethod
    def fit(cls, logs: Sequence[InteractionLog], residuals_a: Sequence[np.ndarray], predictions_a: Sequence[np.ndarray], *,
            cross_validated: bool,
            new_ground_residuals: Mapping[str, Sequence[tuple[InteractionLog, np.ndarray, np.ndarray]]] | None = None,
            turn_scale_radps: float = DEFAULT_TURN_SCALE_RADPS) -> IntervalModel:
        """Spreads from the residuals ``truth - prediction`` (N, 2) of each training log.

        Parameters
        ----------
        logs, residuals_a, predictions_a
            Training logs, their out-of-fold residual currents and the predictions they are
            residuals of (A, (N, 2) each; the basis is relative to the predictions).
        cross_validated : bool
            Whether the residuals are out-of-fold.
        new_ground_residuals : mapping of ground to [(log, residual, prediction)], optional
            Per training ground, residuals (and predictions) of a model fitted without that
            ground (two grounds or more give the new-ground covariance).
        turn_scale_radps : float
        """
        coefs = np.stack([run_coefficients(lg, r, p, turn_scale_radps)
                          for lg, r, p in zip(logs, residuals_a, predictions_a)])
        labels = [str(lg.meta.ground_label).lower() if lg.meta.ground_label is not None else None for lg in logs]
        run_cov = {_POOLED: _shrunk(_second_moment(coefs), coefs.shape[0])}
        for g in sorted({lb for lb in labels if lb is not None}):
            rows = coefs[[i for i, lb in enumerate(labels) if lb == g]]
            if rows.shape[0] >= _MIN_GROUND_RUNS:
                run_cov[g] = _shrunk(_second_moment(rows), rows.shape[0])
        # per-sample spread: what is left after each run's own regime fit
        sq = np.zeros((2, len(SAMPLE_REGIMES)))
        wt = np.zeros(len(SAMPLE_REGIMES))
        acov = np.zeros(_MAX_LAGS + 1)
        dts = []
        for lg, r, p, b in zip(logs, residuals_a, predictions_a, coefs):
            e = np.column_stack([r[:, k] - regime_design(lg, k, turn_scale_radps, p[:, k]) @ b[k] for k in range(2)])
            reg = _regime_of(lg, turn_scale_radps)
            for j in range(len(SAMPLE_REGIMES)):
                sel = reg == j
                sq[:, j] += np.sum(e[sel] ** 2, axis=0)
                wt[j] += sel.sum()
            for lag in range(min(_MAX_LAGS, len(lg) - 1) + 1):
                acov[lag] += float(np.sum(e[lag:] * e[: len(e) - lag]))
            if len(lg) > 1:
                dts.append(float(np.median(np.diff(lg.time_s))))
        overall = np.sqrt(sq.sum(axis=1) / max(wt.sum(), 1.0))
        sample_sd = np.where(wt[None, :] >= 10, np.sqrt(sq / np.maximum(wt[None, :], 1.0)), overall[:, None])
        dt = float(np.median(dts)) if dts else 0.1
        correlation = min(max(_integrated_time(acov, dt), dt), 10.0)
        new_cov, n_grounds = None, 0
        if new_ground_residuals is not None and len(new_ground_residuals) >= 2:
            n_grounds = len(new_ground_residuals)
            means = []
            for pairs in new_ground_residuals.values():
                b = np.stack([run_coefficients(lg, r, p, turn_scale_radps) for lg, r, p in pairs])
                w = np.array([lg.duration_s for lg, _, _ in pairs])
                means.append(np.tensordot(w / w.sum(), b, axes=1))
            # a handful of grounds cannot tell how the columns co-vary: keep the variances only
            new_cov = _diagonal(_second_moment(np.stack(means)))
        interval = cls(float(turn_scale_radps), run_cov, new_cov, sample_sd, float(correlation), bool(cross_validated),
                       len(logs), n_grounds)
        run_cov = {key: cov * interval.charge_scale([i for i, lb in enumerate(labels) if key in (_POOLED, lb)],
                                                    logs, residuals_a, predictions_a, cov)
                   for key, cov in run_cov.items()}
        counts = {key: sum(key in (_POOLED, lb) for lb in labels) for key in run_cov}
        return dataclasses.replace(interval, run_cov=run_cov, run_counts=counts,
                                   run_carry=interval.carry_along_runs(logs, residuals_a))

    def charge_scale(self, runs: Sequence[int], logs: Sequence[InteractionLog], residuals_a: Sequence[np.ndarray],
                     predictions_a: Sequence[np.ndarray], cov: np.ndarray) -> float:
        """The factor on a run covariance ``cov`` that makes it forecast the residual charges of the ``runs`` it was fitted on.

        A run covariance is a second moment of per-run regime coefficients, shrunk towards its diagonal
        where few runs inform it (:func:`_shrunk`: fully below four runs). The columns trade off within a
        run — a gain and an offset fitted on one current level are nearly one degree of freedom — so their
        diagonal alone forecasts a run's charge wider or narrower than any run was off: on the independent
        generator (three training runs a ground) 3 to 12 times the residual charges' spread. The scale of
        the spread is therefore read at the level it is used, the whole-run charge: per run and side, the
        out-of-fold residual charge ``q`` (A s), the variance ``E`` the per-sample noise explains
        (:meth:`noise_charge_var`) and the run spread's forecast ``s = integral(run_sd) dt`` (as
        :meth:`~energy.models.forecast.CurrentForecast.charge` integrates it); the factor is ``(sum(q²) -
        sum(E)) / sum(s²)``. ``1.0`` (the covariance as fitted) where the runs show no run-level part
        above the noise or the factor is not finite.

        Parameters
        ----------
        runs : sequence of int
            Indices of the runs (of ``logs``) the covariance was fitted on.
        logs, residuals_a, predictions_a
            As :meth:`fit`'s.
        cov : ndarray (2, 4, 4)
            The run covariance to scale.
        """
        num = den = 0.0
        for i in runs:
            lg = logs[i]
            if len(lg) < 2:
                continue
            t = lg.time_s
            forecast = _trapezoid(self.run_sd_a(lg, np.asarray(predictions_a[i]), known=True, cov=cov), t, axis=0)
            num += float(np.sum(_trapezoid(np.asarray(residuals_a[i]), t, axis=0) ** 2 - self.noise_charge_var(lg)))
            den += float(np.sum(forecast**2))
        factor = num / den if den > 0 else math.nan
        return factor if math.isfinite(factor) and factor > 0 else 1.0

    def carry_along_runs(self, logs: Sequence[InteractionLog], residuals_a: Sequence[np.ndarray]) -> float | None:
        """:attr:`run_carry` from residual currents ``residuals_a`` (N, 2) of ``logs`` (see the attribute).

        Per run and side the residual charge of each half, ``q1`` and ``q2`` (A s), and the variance
        ``E1``, ``E2`` of each that the per-sample spread explains (:meth:`noise_charge_var_per_sample`); pooled over
        runs and sides, ``sum(q1 q2) / sqrt((sum(q1²) - sum(E1)) (sum(q2²) - sum(E2)))``, clipped to [0, 1].
        """
        parts = []
        for lg, r in zip(logs, residuals_a):
            t = lg.time_s
            first = t < t[0] + 0.5 * (t[-1] - t[0]) if len(lg) else np.zeros(0, dtype=bool)
            if min(np.count_nonzero(first), np.count_nonzero(~first)) < 2:
                continue
            noise = self.noise_charge_var_per_sample(lg)
            parts.append([_trapezoid(r[m], t[m], axis=0) for m in (first, ~first)]
                         + [np.sum(noise[m], axis=0) for m in (first, ~first)])
        if len(parts) < MIN_CARRY_RUNS:
            return None
        q1, q2, e1, e2 = np.moveaxis(np.asarray(parts), 1, 0)  # each (runs, 2)
        signal = (float(np.sum(q1**2) - np.sum(e1)), float(np.sum(q2**2) - np.sum(e2)))
        if not min(signal) > 0:  # no run-level part above the noise (or non-finite residuals): nothing to learn
            return None
        carry = float(np.sum(q1 * q2)) / math.sqrt(signal[0] * signal[1])
        return float(np.clip(carry, 0.0, 1.0)) if math.isfinite(carry) else None

    def noise_charge_var(self, log: InteractionLog) -> np.ndarray:
        """Per side, the variance (A² s²) of ``log``'s residual charge that the per-sample spread explains.

        White noise of correlation time :attr:`correlation_s`: the variance of its integral is ``sum(sd² dt) *
        correlation_s``.
        """
        return np.sum(self.noise_charge_var_per_sample(log), axis=0)

    def noise_charge_var_per_sample(self, log: InteractionLog) -> np.ndarray:
        """Each drive sample's share (N, 2) of :meth:`noise_charge_var` (summed over a stretch: that stretch's)."""
        return self.sample_sd(log) ** 2 * sample_spans_s(log)[:, None] * self.correlation_s

    # ------------------------------------------------------------- queries
    def knows(self, ground: str | None) -> bool:
        """Whether ``ground`` had a run covariance of its own or is pooled among trained grounds."""
        return ground is not None and str(ground).lower() in self.run_cov

    def covariance(self, ground: str | None, *, known: bool) -> np.ndarray:
        """The run-level covariance (2, 4, 4) for a run on ``ground``; ``known=False`` adds the new-ground part."""
        key = str(ground).lower() if ground is not None else _POOLED
        cov = self.run_cov.get(key, self.run_cov[_POOLED]).copy()
        if not known and self.new_ground_cov is not None:
            cov = cov + self.new_ground_cov
        return cov

    def run_sd_a(self, log: InteractionLog, mean_a: np.ndarray, *, known: bool, cov: np.ndarray | None = None) -> np.ndarray:
        """Run-level spread per sample and side (A), shape (N, 2), of the forecast ``mean_a``; ``cov`` overrides the covariance."""
        c = self.covariance(log.meta.ground_label, known=known) if cov is None else cov
        return np.column_stack([_quadratic_sd(regime_design(log, k, self.turn_scale_radps, mean_a[:, k]), c[k])
                                for k in range(2)])

    def sample_sd(self, log: InteractionLog) -> np.ndarray:
        """Per-sample spread (A), shape (N, 2)."""
        reg = _regime_of(log, self.turn_scale_radps)
        return self.sample_sd_a[:, reg].T.copy()

    # --------------------------------------------------------- persistence
    def to_plain(self) -> dict[str, Any]:
        return {"turn_scale_radps": self.turn_scale_radps, "run_cov": dict(self.run_cov),
                "new_ground_cov": self.new_ground_cov, "sample_sd_a": self.sample_sd_a,
                "correlation_s": self.correlation_s, "cross_validated": self.cross_validated, "n_runs": self.n_runs,
                "n_grounds": self.n_grounds, "run_carry": self.run_carry,
                "run_counts": None if self.run_counts is None else dict(self.run_counts)}

    @classmethod
    def from_plain(cls, d: Mapping[str, Any]) -> IntervalModel:
        """Rebuild from :meth:`to_plain` (raises ValueError / KeyError / TypeError on bad content)."""
        k = len(REGIME_COLUMNS)

        def cov(name: str, value: Any) -> np.ndarray:
            arr = np.asarray(value, dtype=np.float64)
            if arr.shape != (2, k, k) or not np.all(np.isfinite(arr)):
                raise ValueError(f"{name} must be a finite (2, {k}, {k}) array")
            check_covariances(name, arr, MAX_RUN_VARIANCE)
            return arr

        run_cov = {str(g): cov(f"run_cov[{g}]", v) for g, v in dict(d["run_cov"]).items()}
        if _POOLED not in run_cov:
            raise ValueError("run_cov lacks the pooled entry")
        new = d["new_ground_cov"]
        sd = np.asarray(d["sample_sd_a"], dtype=np.float64)
        if sd.shape != (2, len(SAMPLE_REGIMES)) or not np.all(np.isfinite(sd)) or np.any(sd < 0):
            raise ValueError("sample_sd_a must be a finite non-negative (2, 3) array")
        if np.any(sd > MAX_SAMPLE_SD_A):
            raise ValueError(f"sample_sd_a holds {float(sd.max()):.3g} A, more than a drive current's plausible spread "
                             f"({MAX_SAMPLE_SD_A:g} A): not the spread of a current model")
        scale, corr = float(d["turn_scale_radps"]), float(d["correlation_s"])
        if not (math.isfinite(scale) and scale > 0 and math.isfinite(corr) and corr > 0):
            raise ValueError("turn_scale_radps and correlation_s must be finite and > 0")
        if scale > 100.0 or corr > 3600.0:
            raise ValueError(f"turn_scale_radps {scale:.3g} rad/s or correlation_s {corr:.3g} s is beyond any robot's "
                             "(at most 100 rad/s and 3600 s)")
        return cls(scale, run_cov, None if new is None else cov("new_ground_cov", new), sd, corr,
                   check_bool("cross_validated", d["cross_validated"]), check_int("n_runs", d["n_runs"], low=0),
                   check_int("n_grounds", d.get("n_grounds", 0), low=0),  # absent before it was recorded
                   None if d.get("run_carry") is None else check_real("run_carry", d["run_carry"], low=0.0, high=1.0),
                   _run_counts(d.get("run_counts"), run_cov))  # both absent before they were recorded


def _run_counts(value: Any, run_cov: Mapping[str, np.ndarray]) -> dict[str, int] | None:
    """The saved :attr:`IntervalModel.run_counts` (None: absent), one count >= 1 per key of ``run_cov``."""
    if value is None:
        return None
    counts = {str(k): check_int(f"run_counts[{k}]", v, low=1) for k, v in dict(value).items()}
    if set(counts) != set(run_cov):
        raise ValueError(f"run_counts must have one count per run covariance ({sorted(run_cov)}), got {sorted(counts)}")
    return counts
