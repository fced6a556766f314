"""In-run adaptation of a fitted current model: a small regime residual fitted on the first seconds of a run.

:class:`AdaptedCurrentModel` wraps a fitted model (never modified) and adds, per side, a
correction fitted on a short stretch of new data (``fit(logs)``: seconds, not a retraining).
``model.adapt(log_prefix, **options)`` (:meth:`CurrentModel.adapt`) is the one way to adapt
a model: it builds and fits this class with the options checked; adapting an adapted model
refits the correction on its base, it does not stack corrections.

Methods (:data:`ADAPT_METHODS`), chosen by measurement on the BorealTC logs (leave one run
out per ground, the default estimator adapted on the first 10 / 20 / 40 s of each held-out
run and scored on the rest; the README has the table):

- ``"partition"`` (default): per side, the residual ``measured - predicted`` is regressed on
  the partition of the motion ``[1 - m, |v|, m, m * outer]`` with ``m = tanh(|omega| /
  turn_scale_radps)`` (0 straight, 1 turning) and ``outer`` 1 on the outer side of a turn,
  by ridge regression whose penalty ``prior_s`` is worth that many seconds of data showing
  no residual: straight driving (and rest) and turning get a level each, so a regime the
  prefix did not drive keeps its correction near zero (a prefix that only pivots in place
  leaves straight driving at its prior) instead of inheriting one fitted on the other regime
  — the failure of a single gain. Chosen by the rule of the defaults (the least worst harm to
  the unadapted forecast at median or p90 after 20 and 40 s, ties within a point by the mean
  error), each ground held out of the choice: with ``shrink="prior"`` it is chosen for every
  BorealTC ground held out and for the independent generator's grounds, and it harms no ground
  by more than 1.5 points (snow's p90 at 20 s 59.7 % against 62.2 % unadapted; ``"regime"``:
  70.4 %). Its cost: each level learns from its own regime's seconds only, so on prefixes that
  drove both it moves less than ``"regime"`` (the generator's grounds pooled 22.4 / 74.2 %
  against 18.7 / 56.7 % at 20 s, both below the unadapted 30.7 / 92.3 %; docs/results.md).
- ``"regime"``: the same on ``[1, |v|, m, m * outer]``, one offset shared by every regime (the
  default before): the ridge splits a pivot's residual between the offset and the turning
  column and half of it lands on straight driving and rest. Three rules meant to keep the
  partition's fix with this one's gain where a prefix drove both (a common level shared by the
  prefix's regime balance; the regime update scaled by the regime overlap of prefix and run; a
  switch on the balance chosen on other grounds) were measured and dropped: each beats it held
  out on BorealTC and loses to it on the generator's grounds.
- ``"regime_gain"``: per side a gain on the prediction per regime, the residual regressed on
  ``[(1 - m) * predicted, m * predicted]`` by the same ridge (each column penalised on its own
  current's scale, as ``"gain_offset"``'s gain): a ground that scales the drive's resistance
  (a softer ground: more rolling resistance, a scale on every current) is followed in proportion
  to what the model predicts, straight driving and turning apart so that a prefix that pivots
  does not set the straight gain. Few shots, each ground held out (docs/results.md, "A gain per
  regime"): on the independent generator's grounds, whose ground scales the resistance, it
  forecasts far better than the default (pooled total charge median / p90 after 20 s 14.9 / 28.4 %
  against 21.2 / 71.7 %; the gain baseline 11.6 / 31.2 %), and on BorealTC's flooring (21.3 /
  47.1 % against 30.8 / 60.8 %), but it harms snow (32.2 / 75.9 % against 28.4 / 62.2 % not
  adapting), so by the rule of the defaults it is an option, not the default.
- ``"gain"``: one gain per side, the measured over the predicted charge of the prefix (the
  baseline every update is compared with).
- ``"gain_offset"``: per side ``a * predicted + b`` by the same ridge as ``"regime"``.
- ``"bayes"``: Bayesian regression of the residual on the regime basis of
  :mod:`energy.models.uncertainty` with the prior the base model learned across its
  training runs and grounds (its :class:`~energy.models.uncertainty.IntervalModel`): the
  residual of the new data is a ground offset (prior: the new-ground covariance, or none
  on a ground the model knows) plus this run's own offset (prior: the run covariance),
  seen through per-sample noise whose correlation time discounts seconds of data, not
  samples. ``scope="run"`` forecasts the rest of the same run (ground offset + the run's own as
  far as it carries along the run, :attr:`~energy.models.uncertainty.IntervalModel.run_carry`);
  ``scope="ground"`` forecasts *other* runs on the ground (ground offset only, the run
  spread kept in the interval). It needs a base model with an interval
  (:attr:`CurrentModel.gives_interval`), and its forecast carries the posterior interval.

``shrink`` (:data:`ADAPT_SHRINKS`; the point updates, with a base model that gives an interval)
moves a correction only as far as the evidence carries it. Per side, over the prefix: ``obs`` the
charge its residual adds up to (A s); ``E`` the variance of that charge the per-sample noise
explains (counted in correlation times); ``R`` what a run's own offset adds to it, learned across
the training runs; ``G`` what a ground's offset adds, learned across the training grounds (the
new-ground spread; zero on a ground the model drove). The correction is scaled by

- ``"prior"`` (default): the share of the prefix's residual that carries to the forecast,
  ``G / (G + R + E)`` forecasting other runs on the ground (``scope="ground"``), ``(G + R) / (G +
  R + E)`` the rest of the same run (``scope="run"``) — the posterior mean of a Gaussian offset
  whose spreads are the learned ones. It does not look at ``obs``: the prefix of one run cannot
  say whether its offset is the ground's or its own, the spreads learned over many runs and
  grounds can. A model trained on one ground learned no ground spread: on a ground it never
  drove it falls back to ``"evidence"``.
- ``"evidence"``: the positive-part James–Stein factor ``max(0, 1 - V / obs**2)`` with ``V = E``
  (+ ``R`` with ``scope="ground"``): ``G`` estimated from the prefix alone.
- ``"none"``: the correction as fitted.

**The interval.** A point update's forecast keeps the base's per-sample spread and conditions the
run-level spread on the prefix (:meth:`AdaptedCurrentModel.correct_distribution`): under the learned
spreads the offset the forecast misses has a posterior given the prefix's residual charge ``obs``, and
the forecast error's variance is that posterior's plus the square of how far the update's correction
lies from its mean. A prefix near its forecast narrows the interval; one far from it that the update
holds back from (the ridge, the shrink) keeps it wide. Forecasting other runs on the prefix's ground
(``scope="ground"``) only the ground's offset is conditioned, the next run's own kept whole; measured
held out on the BorealTC grounds and the independent generator's (docs/results.md, "The interval given
the prefix"): a proper score (the log predictive density of the total charge) better than with the
base's spread kept on seven grounds of nine, worse on the two whose spread the training grounds
underestimate (snow: its 80 % interval covers 74–76 % against 78–80 %). Forecasting the rest of the
prefix's run (``scope="run"``) the run's own offset is conditioned too, as far as it carries along a
run: :attr:`~energy.models.uncertainty.IntervalModel.run_carry`, the correlation of the two halves of
the training runs (a run's offset drifts along it: taken as constant, the 80 % intervals of the rest of
the run covered 73 % on the BorealTC logs, the base's spread 88 %; with the learned carry 76–88 %,
docs/results.md, "The rest of the run given its prefix").

Chosen by measurement (docs/results.md, "Forecasts you can bank on"): few shots on the BorealTC
grounds, each ground held out of the choice in turn, the update whose worst harm to the
unadapted forecast (median or p90 of total charge, 20 and 40 s) on the two other grounds is least
— ties within the 1 point the target allows broken by the lower mean error — is ``"prior"`` for
every choice of two; on the grounds of the independent generator (held out of every choice) it
raises no ground's error by more than a point and forecasts better than the evidence shrink
(pooled, 40 s: 13.7 / 54.0 % against 20.2 / 64.4 %, median / p90). Choosing on the prefix
itself (fit on its first half, keep the correction where it beats the unadapted forecast of the
second half by more than its noise) was measured and dropped: within one run a run's own offset
passes that check as well as the ground's. So was shrinking once — the ridge as the prior
precision of the level, ``E T / (G + R)`` s instead of ``prior_s``, then ``G / (G + R)``: ahead of
``"prior"`` held out on BorealTC (on the partition), behind it on the generator's grounds (the
40-s median; harm after 10 s, where a ridge of a second lets the regime columns follow the prefix).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np

from terrawatt_base.checks import check_bool, check_choice, check_int, check_real, check_text, real_array
from terrawatt_base.errors import DataError, InvalidParameterError

from ..logs import InteractionLog
from ..power import trapezoid as _trapezoid
from .base import CurrentModel, ModelRecord, TrainedOn, check_logs, log_currents
from .forecast import CurrentForecast
from .loading import model_class
from .uncertainty import MAX_RUN_VARIANCE, check_covariances, regime_design, sample_spans_s

__all__ = [
    "ADAPT_METHODS",
    "ADAPT_SCOPES",
    "ADAPT_SHRINKS",
    "MIN_ADAPT_SECONDS",
    "MIN_ADAPT_SAMPLES",
    "AdaptedCurrentModel",
    "evidence_parts",
    "regime_basis",
]

#: Update methods of :class:`AdaptedCurrentModel`, the default first.
ADAPT_METHODS = ("partition", "regime", "regime_gain", "gain", "gain_offset", "bayes")
#: What a ``"bayes"`` update forecasts: the rest of the same run, or other runs on the ground.
ADAPT_SCOPES = ("run", "ground")
#: How a point update is scaled by its evidence (module docstring), the default first.
ADAPT_SHRINKS = ("prior", "evidence", "none")
_NOISE_FLOOR_A = 0.05  # least per-sample spread the Bayesian update assumes (A)
_MAX_EVIDENCE = 1e12  # a prefix's residual charge (A s) or its variances (A² s²) beyond this are no log's: a forged file
#: Effective samples' worth of belief that a new stretch of data is as noisy as the training runs
#: (``"bayes"``: the noise ratio of the data is shrunk towards 1 by this many samples).
NOISE_PRIOR_SAMPLES = 10.0
#: Least duration (s) of new data an adaptation accepts by default (``min_seconds``).
MIN_ADAPT_SECONDS = 5.0
#: Least number of drive samples (both streams overlapping) an adaptation accepts.
MIN_ADAPT_SAMPLES = 10


def regime_basis(log: InteractionLog, side: int, turn_scale_radps: float) -> np.ndarray:
    """``[1, |v|, m, m * outer]`` per sample for one side (0 left, 1 right): the basis of the ``"regime"`` update.

    ``m = tanh(|omega| / turn_scale_radps)`` (0 straight, 1 turning); ``outer`` is 1 on the
    outer side of a turn. Shape (N, 4).
    """
    m = np.tanh(np.abs(log.omega_radps) / turn_scale_radps)
    sign = -1.0 if side == 0 else 1.0
    outer = (sign * log.omega_radps > 0).astype(np.float64)
    return np.column_stack([np.ones(len(log)), np.abs(log.v_mps), m, m * outer])


def _precision(cov: np.ndarray) -> np.ndarray:
    """Inverse of a prior covariance, regularised: a direction with no learned spread gets a tight but finite prior."""
    scale = max(float(np.trace(cov)) / cov.shape[0], 1e-6)
    return np.linalg.inv(cov + 1e-3 * scale * np.eye(cov.shape[0]))


def evidence_parts(base: CurrentModel, logs: Sequence[InteractionLog], preds: Sequence[np.ndarray],
                   truths: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per side, over a prefix: its residual charge and the variances of that charge the base model's interval expects.

    Parameters
    ----------
    base : CurrentModel
        A fitted model with an interval (``base.interval_``).
    logs, preds, truths
        The prefix's logs, the base model's predictions on them and the measured currents ((N, 2) each).

    Returns
    -------
    obs : ndarray (2,)
        ``integral(measured - predicted) dt`` (A s).
    noise, run, ground : ndarray (2,)
        Variances (A² s²) of that charge: the per-sample noise (white noise of correlation time
        ``correlation_s``: the variance of its integral is ``sum(sd² dt) * correlation_s``), a run's own
        offset (the run covariance of the prefix's ground, or the pooled one) and a ground's offset
        (the new-ground covariance; zero on a ground the model drove, or without one).
    """
    interval = base.interval_
    known = base.knows_ground(logs[0].meta.ground_label)
    obs, noise, run, ground = np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2)
    for lg, p, y in zip(logs, preds, truths):
        t = lg.time_s
        obs += _trapezoid(y - p, t, axis=0)
        noise += interval.noise_charge_var(lg)
        run += _trapezoid(interval.run_sd_a(lg, p, known=True), t, axis=0) ** 2
        if not known and interval.new_ground_cov is not None:
            ground += _trapezoid(interval.run_sd_a(lg, p, known=True, cov=interval.new_ground_cov), t, axis=0) ** 2
    return obs, noise, run, ground


class AdaptedCurrentModel(CurrentModel):
    """A fitted current model plus a per-side correction fitted on a short stretch of new data.

    ``fit(logs)`` fits the correction on ``logs`` (the first seconds of a run, say); the
    ``base`` model is used as it is and never modified. ``predict`` is the base prediction
    plus the correction, clamped at 0 when every current of the adaptation data was >= 0
    (drivers that log motoring current only).

    Parameters
    ----------
    base : CurrentModel
        The fitted model to adapt (an AdaptedCurrentModel is unwrapped to its own base:
        corrections are refitted, not stacked).
    method : {"partition", "regime", "regime_gain", "gain", "gain_offset", "bayes"}
        The update (see the module docstring).
    prior_s : float
        Ridge penalty of the regression updates (all but ``"gain"`` and ``"bayes"``), in seconds of data showing no
        residual (> 0): larger keeps the model closer to the base.
    turn_scale_radps : float
        ``|omega|`` (rad/s) at which ``"regime"`` counts a sample as 76 % turning (> 0).
    min_seconds : float
        Least duration of adaptation data (s, >= 0); less raises a DataError.
    scope : {"run", "ground"}
        What the update forecasts: the rest of the run it was fitted on, or other runs on the
        same ground (see the module docstring); the point updates use it with ``shrink`` and for
        their interval (conditioned on the prefix).
    shrink : {"prior", "evidence", "none"}
        How a point update's correction is scaled by the evidence of the prefix (module
        docstring; ``True`` / ``False`` in files from before are ``"evidence"`` / ``"none"``);
        ignored by ``"bayes"`` (its posterior already weighs the evidence) and where the base
        model gives no interval.

    Attributes
    ----------
    coefficients_ : numpy.ndarray, shape (2, k)
        Per side: the gain (``"gain"``), ``[gain - 1, offset]`` (``"gain_offset"``), ``[straight gain - 1,
        turning gain - 1]`` (``"regime_gain"``) or the
        regime residual coefficients ``[offset A, per |v| A s/m, turning A, outer turning A]``
        (``"partition"``: ``[straight level A, per |v| A s/m, turning level A, outer turning A]``);
        ``"bayes"``: the posterior mean of the ground offset then the run offset (8 columns).
    posterior_cov_ : numpy.ndarray, shape (2, 8, 8), or None
        ``"bayes"``: their posterior covariance per side.
    noise_ratio_ : float
        ``"bayes"``: how much noisier (> 1) or calmer the adaptation data are than the training
        runs, shrunk towards 1; scales the forecast's spreads (1 for other methods).
    ground_ : str or None
        The ground label of the adaptation data.
    adapted_on_s_ : float
        Duration of the adaptation data (s).
    n_samples_ : int
        Its drive samples.
    nonnegative_ : bool
        Whether predictions are clamped at 0.
    shrink_ : numpy.ndarray, shape (2,)
        Per side, the factor the correction was scaled by (1 without ``shrink``).
    evidence_ : numpy.ndarray, shape (4, 2), or None
        The point updates with a base that gives an interval: per side the prefix's residual
        charge ``obs`` (A s) and the variances ``E``, ``R``, ``G`` of it (A² s²,
        :func:`evidence_parts`), which the forecast's interval is conditioned on; None otherwise.

    Examples
    --------
    Usage (needs a fitted model and a log, so not run as a doctest)::

        adapted = model.adapt(log.slice(log.time_s[0], log.time_s[0] + 20.0))
        adapted.predict(log)
    """

    _param_names = ("base", "method", "prior_s", "turn_scale_radps", "min_seconds", "scope", "shrink")
    _n_coefficients: ClassVar[dict[str, int]] = {"regime": 4, "gain": 1, "gain_offset": 2, "bayes": 8, "partition": 4,
                                                 "regime_gain": 2}

    def __init__(self, base: CurrentModel, method: str = ADAPT_METHODS[0], prior_s: float = 20.0,
                 turn_scale_radps: float = 0.3, min_seconds: float = MIN_ADAPT_SECONDS, scope: str = "run",
                 shrink: str = ADAPT_SHRINKS[0]) -> None:
        self.base = base
        self.method = method
        self.prior_s = prior_s
        self.turn_scale_radps = turn_scale_radps
        self.min_seconds = min_seconds
        self.scope = scope
        self.shrink = shrink

    @classmethod
    def adapting(cls, model: CurrentModel, log_prefix: InteractionLog | Sequence[InteractionLog],
                 **options: Any) -> AdaptedCurrentModel:
        """``cls(model, **options).fit(log_prefix)`` with the option names checked (what ``model.adapt`` calls).

        Raises
        ------
        InvalidParameterError
            An option that is not a parameter of this class (the message lists them), or
            ``log_prefix`` is not logs; and as :meth:`fit`.
        """
        unknown = sorted(set(options) - set(cls._param_names[1:]))
        if unknown:
            raise InvalidParameterError(f"unknown adaptation option(s) {unknown!r}; expected names from {list(cls._param_names[1:])!r}")
        return cls(model, **options).fit(check_logs(log_prefix, "log_prefix"))

    # -------------------------------------------------------------- validation
    def _check_params(self) -> CurrentModel:
        if not isinstance(self.base, CurrentModel) or not self.base.is_fitted:
            raise InvalidParameterError(f"base must be a fitted CurrentModel, got {self.base!r:.80}")
        check_choice("method", self.method, ADAPT_METHODS)
        check_real("prior_s", self.prior_s, low=0.0, low_inclusive=False)
        check_real("turn_scale_radps", self.turn_scale_radps, low=0.0, low_inclusive=False)
        check_real("min_seconds", self.min_seconds, low=0.0)
        check_choice("scope", self.scope, ADAPT_SCOPES)
        check_choice("shrink", self.shrink, ADAPT_SHRINKS)
        base = self.base
        return base.base if isinstance(base, AdaptedCurrentModel) else base

    def _check_amount(self, logs: list[InteractionLog]) -> None:
        duration = sum(lg.duration_s for lg in logs)
        samples = sum(len(lg) for lg in logs)
        if duration < self.min_seconds or samples < MIN_ADAPT_SAMPLES:
            raise DataError(
                f"adapting needs at least {self.min_seconds:g} s and {MIN_ADAPT_SAMPLES} drive samples of new data "
                f"(min_seconds / log_prefix); got {duration:.3g} s and {samples} samples — give a longer log prefix"
            )

    # ------------------------------------------------------------------- fit
    def _fit(self, logs: list[InteractionLog]) -> None:
        base = self._check_params()
        self._check_amount(logs)
        preds = [base.predict(lg) for lg in logs]
        truths = [log_currents(lg) for lg in logs]
        coef = np.zeros((2, self._n_coefficients[self.method]))
        self.posterior_cov_ = None
        self.noise_ratio_ = 1.0
        if self.method == "bayes":
            coef, self.posterior_cov_, self.noise_ratio_ = self._fit_bayes(base, logs, preds, truths)
        for k in range(2 if self.method != "bayes" else 0):
            if self.method == "gain":
                q_pred = sum(float(_trapezoid(p[:, k], lg.time_s)) for p, lg in zip(preds, logs))
                q_true = sum(float(_trapezoid(y[:, k], lg.time_s)) for y, lg in zip(truths, logs))
                if not q_pred > 0:
                    raise DataError(
                        f"the base model predicts no charge on the {('left', 'right')[k]} side of the adaptation data "
                        f"({q_pred:.3g} A s); a gain cannot be fitted — use method='regime'"
                    )
                coef[k, 0] = q_true / q_pred
                continue
            x = np.concatenate([self._design(lg, p, k) for lg, p in zip(logs, preds)])
            r = np.concatenate([y[:, k] - p[:, k] for y, p in zip(truths, preds)])
            w = np.concatenate([sample_spans_s(lg) for lg in logs])
            scale = np.ones(x.shape[1])
            if self.method == "gain_offset":  # the gain's column is in A: penalise it on the current's scale
                scale[0] = max(float(np.average(np.abs(x[:, 0]), weights=w)), 0.5) ** 2
            elif self.method == "regime_gain":  # both columns are currents: each on its own regime's scale
                scale = np.maximum(np.average(np.abs(x), axis=0, weights=w), 0.5) ** 2
            a = (x * w[:, None]).T @ x + np.diag(self.prior_s * scale)
            coef[k] = np.linalg.solve(a, (x * w[:, None]).T @ r)
        self.shrink_ = np.ones(2)
        self.evidence_ = None
        if self.method != "bayes" and base.gives_interval:
            self.evidence_ = np.stack(evidence_parts(base, logs, preds, truths))
        if self.shrink != "none" and self.evidence_ is not None:
            self.shrink_ = self._evidence(base, logs[0].meta.ground_label, self.evidence_)
            if self.method == "gain":  # a gain moves from 1
                coef = 1.0 + (coef - 1.0) * self.shrink_[:, None]
            else:
                coef = coef * self.shrink_[:, None]
        if not np.all(np.isfinite(coef)):
            raise DataError("the adaptation data gave a non-finite correction (non-finite currents or inputs?)")
        self.coefficients_ = coef
        self.ground_ = logs[0].meta.ground_label
        self.adapted_on_s_ = float(sum(lg.duration_s for lg in logs))
        self.n_samples_ = int(sum(len(lg) for lg in logs))
        self.nonnegative_ = bool(all(np.all(y >= 0) for y in truths))

    def _evidence(self, base: CurrentModel, ground_label: str | None, parts: np.ndarray) -> np.ndarray:
        """Per side, the factor the correction is scaled by (``shrink``, module docstring), in [0, 1]."""
        obs, noise, run, ground = parts
        # a new ground and no ground spread learned (one training ground): the prior cannot say; the evidence can
        unlearned = base.interval_.new_ground_cov is None and not base.knows_ground(ground_label)
        if self.shrink == "prior" and not unlearned:
            carried = ground if self.scope == "ground" else ground + run
            total = ground + run + noise
            lam = np.divide(carried, total, out=np.zeros(2), where=total > 0)
        else:  # "evidence": a run's own offset does not carry to other runs
            var = noise + run if self.scope == "ground" else noise
            with np.errstate(divide="ignore", invalid="ignore"):
                lam = np.where(obs**2 > 0, 1.0 - var / obs**2, 0.0)
        return np.clip(np.nan_to_num(lam, nan=0.0), 0.0, 1.0)

    def _fit_bayes(self, base: CurrentModel, logs: list[InteractionLog], preds: list[np.ndarray],
                   truths: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, float]:
        """Posterior mean (2, 8) and covariance (2, 8, 8) of ``[ground offset, run offset]`` per side, and the noise ratio.

        Two passes: the first with the per-sample spread the base model learned; the ratio of
        the residual left by it to that spread (shrunk towards 1 by :data:`NOISE_PRIOR_SAMPLES`
        effective samples) says whether this ground is noisier or calmer than the training
        grounds, and the second pass weighs the data — and the forecast scales the run and
        sample spreads — by it.
        """
        interval = getattr(base, "interval_", None)
        if interval is None or not base.gives_interval:
            raise DataError(f"method='bayes' needs a base model with a fitted interval; this {type(base).__name__} has "
                            f"none (refit it, or use method='regime')")
        ground = logs[0].meta.ground_label
        known = base.knows_ground(ground)
        run_cov = interval.covariance(ground, known=True)
        if known:
            ground_cov = np.zeros_like(run_cov)
        else:
            ground_cov = interval.new_ground_cov if interval.new_ground_cov is not None else run_cov
        k_cols = run_cov.shape[1]
        xs = [np.concatenate([regime_design(lg, k, interval.turn_scale_radps, p[:, k]) for lg, p in zip(logs, preds)])
              for k in range(2)]
        rs = [np.concatenate([y[:, k] - p[:, k] for y, p in zip(truths, preds)]) for k in range(2)]
        sds = [np.maximum(np.concatenate([interval.sample_sd(lg)[:, k] for lg in logs]), _NOISE_FLOOR_A) for k in range(2)]
        dt = np.concatenate([sample_spans_s(lg) for lg in logs])

        def solve(ratio: float) -> tuple[np.ndarray, np.ndarray]:
            mean = np.zeros((2, 2 * k_cols))
            cov = np.zeros((2, 2 * k_cols, 2 * k_cols))
            for k in range(2):
                w = dt / interval.correlation_s / (ratio * sds[k] ** 2)
                xx = np.concatenate([xs[k], xs[k]], axis=1)
                prior = np.zeros((2 * k_cols, 2 * k_cols))
                prior[:k_cols, :k_cols] = _precision(ratio * ground_cov[k])
                prior[k_cols:, k_cols:] = _precision(ratio * run_cov[k])
                c = np.linalg.inv((xx * w[:, None]).T @ xx + prior)
                cov[k] = 0.5 * (c + c.T)
                mean[k] = cov[k] @ ((xx * w[:, None]).T @ rs[k])
            return mean, cov

        mean, _ = solve(1.0)
        left = [rs[k] - np.concatenate([xs[k], xs[k]], axis=1) @ mean[k] for k in range(2)]
        observed = float(sum(np.sum(dt * left[k] ** 2) for k in range(2)) / sum(np.sum(dt * sds[k] ** 2) for k in range(2)))
        n_eff = float(dt.sum()) / interval.correlation_s
        ratio = (n_eff * observed + NOISE_PRIOR_SAMPLES) / (n_eff + NOISE_PRIOR_SAMPLES)
        mean, cov = solve(ratio)
        return mean, cov, float(ratio)

    def _bayes_parts(self) -> tuple[np.ndarray, np.ndarray]:
        """Per side, the coefficients (2, 4) the forecast adds and their covariance (2, 4, 4) for its scope.

        Other runs (``scope="ground"``): the ground's offset, and the next run's own offset whole. The rest of the
        run (``scope="run"``): the ground's offset plus the run's own as far as it carries along the run
        (:attr:`~energy.models.uncertainty.IntervalModel.run_carry` ``c``; 1, an offset constant along the run,
        where none was learned): ``g + c r``, and ``1 - c²`` of the run spread the prefix does not speak for.
        """
        k_cols = self.coefficients_.shape[1] // 2
        interval = self.base_model.interval_
        # a run's own offset: the ground's run spread where the model learned one, else the pooled one
        run_cov = self.noise_ratio_ * interval.covariance(self.ground_, known=True)
        if self.scope == "ground":
            return self.coefficients_[:, :k_cols], self.posterior_cov_[:, :k_cols, :k_cols] + run_cov
        carry = 1.0 if interval.run_carry is None else interval.run_carry
        lift = np.concatenate([np.eye(k_cols), carry * np.eye(k_cols)], axis=1)
        return (self.coefficients_[:, :k_cols] + carry * self.coefficients_[:, k_cols:],
                np.einsum("ij,sjk,lk->sil", lift, self.posterior_cov_, lift) + (1.0 - carry**2) * run_cov)

    @property
    def uses_vibration(self) -> bool:
        """The base model's."""
        return self.base_model.uses_vibration

    @property
    def gives_interval(self) -> bool:
        """Whether the base model gives one (a ``"bayes"`` update then gives its posterior interval)."""
        return self.base_model.gives_interval

    def _predict_distribution(self, log: InteractionLog) -> CurrentForecast:
        return self.correct_distribution(log, self.base_model.predict_distribution(log))  # one base prediction

    def correct_distribution(self, log: InteractionLog, base_forecast: CurrentForecast) -> CurrentForecast:
        """The adapted forecast of ``log`` given the base model's forecast of it (no new base prediction).

        The mean is :meth:`correct` of the base mean. A ``"bayes"`` update replaces the
        base's learned run spread by its posterior (the members' disagreement is kept);
        other updates are point corrections and keep the base's spreads.

        Raises
        ------
        NotFittedError, InvalidParameterError
            As :meth:`correct`; ``base_forecast`` is not a CurrentForecast of ``log``.
        """
        if not isinstance(base_forecast, CurrentForecast) or base_forecast.mean_a.shape != (len(log), 2):
            raise InvalidParameterError(f"base_forecast must be the base model's CurrentForecast of the log, got "
                                        f"{base_forecast!r:.80}")
        mean = self.correct(log, base_forecast.mean_a)
        if self.method != "bayes":
            return CurrentForecast(log.time_s, mean, self._posterior_run_sd(log, base_forecast, mean),
                                   base_forecast.sample_sd_a, base_forecast.dof)
        base = self.base_model
        interval = base.interval_
        known = base.knows_ground(log.meta.ground_label)
        own = interval.run_sd_a(log, base_forecast.mean_a, known=known)
        ensemble = np.sqrt(np.maximum(base_forecast.run_sd_a**2 - own**2, 0.0))  # what the members disagree on
        _, cov = self._bayes_parts()
        run = np.sqrt(interval.run_sd_a(log, base_forecast.mean_a, known=True, cov=cov) ** 2 + ensemble**2)
        return CurrentForecast(log.time_s, mean, run, base_forecast.sample_sd_a * math.sqrt(self.noise_ratio_),
                               base_forecast.dof)

    def _posterior_run_sd(self, log: InteractionLog, base_forecast: CurrentForecast, mean: np.ndarray) -> np.ndarray:
        """A point update's run-level spread of ``log`` given what the prefix showed (module docstring, "The interval").

        Per side, the prefix's residual charge is ``obs = g + r + e`` (variances ``G``, ``R``, ``E``); the
        offset the forecast of ``log`` misses is ``g' + r'``: the same ground's offset (prior variance
        ``Vg`` over ``log``) and, forecasting the rest of the prefix's run (``scope="run"``), the run's own
        offset carried along it with the correlation :attr:`~energy.models.uncertainty.IntervalModel.run_carry`
        (variance ``Vr``); forecasting another run (``scope="ground"``) that run's own offset is independent
        and stays whole. Given ``obs`` the conditioned offset has the mean ``C / (G + R + E) obs`` with ``C =
        sqrt(Vg G) + carry sqrt(Vr R)`` and the variance ``P - C² / (G + R + E)`` (``P`` its prior
        variance); the update's correction of ``log``, ``d``, departs from that mean by ``b``, so the
        forecast error's variance is the posterior's plus ``b²`` and the conditioned part of the spread is
        scaled by ``(posterior + b²) / P`` — narrower where the update follows the evidence, wider where it
        holds back from a prefix that lay far from the forecast (or carries more of it than the run's drift
        lets through). The members' disagreement stays whole. The base's spread where there is nothing to
        condition on: no prefix evidence (a model file from before it was kept, a base without an
        interval), another run of a ground the model drove (``G = 0``), the rest of a run with no carry
        learned (a base from before it was, or one trained on fewer than three runs).
        """
        run_sd = base_forecast.run_sd_a
        if self.evidence_ is None or not base_forecast.has_interval:
            return run_sd
        obs, noise, run, ground = self.evidence_
        base = self.base_model
        interval = base.interval_
        new_ground = not base.knows_ground(log.meta.ground_label) and interval.new_ground_cov is not None
        carry = interval.run_carry if self.scope == "run" else 0.0
        if carry is None or (self.scope == "ground" and not (new_ground and np.any(ground > 0))):
            return run_sd
        zero = np.zeros_like(run_sd)
        ground2 = (interval.run_sd_a(log, base_forecast.mean_a, known=True, cov=interval.new_ground_cov) ** 2
                   if new_ground else zero)
        run2 = interval.run_sd_a(log, base_forecast.mean_a, known=True) ** 2 if self.scope == "run" else zero
        held = ground2 + run2  # the part the prefix conditions
        rest2 = np.maximum(run_sd**2 - held, 0.0)  # the next run's own offset (scope "ground"), the members' disagreement
        t = log.time_s
        prior_sd = _trapezoid(np.sqrt(held), t, axis=0)  # sqrt(P) per side (A s)
        cross = (_trapezoid(np.sqrt(ground2), t, axis=0) * np.sqrt(ground)
                 + carry * _trapezoid(np.sqrt(run2), t, axis=0) * np.sqrt(run))
        d = _trapezoid(mean - base_forecast.mean_a, t, axis=0)
        total = ground + run + noise
        with np.errstate(divide="ignore", invalid="ignore"):
            gain = np.where(total > 0, cross / total, 0.0)
            post = np.maximum(prior_sd**2 - gain * cross, 0.0)
            factor = np.where(prior_sd > 0, (post + (gain * obs - d) ** 2) / prior_sd**2, 1.0)
        return np.sqrt(rest2 + factor[None, :] * held)

    def _training_summary(self, logs: list[InteractionLog]) -> TrainedOn:
        own = TrainedOn.from_logs(logs)
        base = getattr(self.base_model, "trained_on_", None)
        return own if base is None else base.merged(own)

    def ground_vibration(self, ground: str) -> tuple[np.ndarray, np.ndarray] | None:
        """The base model's (:meth:`CurrentModel.ground_vibration`)."""
        return self.base_model.ground_vibration(ground)

    def _design(self, log: InteractionLog, pred: np.ndarray, side: int) -> np.ndarray:
        if self.method == "bayes":
            return regime_design(log, side, self.base_model.interval_.turn_scale_radps, pred[:, side])
        if self.method == "gain_offset":
            return np.column_stack([pred[:, side], np.ones(len(log))])
        if self.method == "regime_gain":  # a gain per regime: [(1 - m) pred, m pred]
            m = np.tanh(np.abs(log.omega_radps) / self.turn_scale_radps)
            return np.column_stack([(1.0 - m) * pred[:, side], m * pred[:, side]])
        x = regime_basis(log, side, self.turn_scale_radps)
        if self.method == "partition":  # straight and turning levels apart: [1 - m, |v|, m, m * outer]
            x[:, 0] -= x[:, 2]
        return x

    # --------------------------------------------------------------- predict
    @property
    def base_model(self) -> CurrentModel:
        """The model the correction is added to (``base``, unwrapped when it was adapted itself)."""
        return self.base.base if isinstance(self.base, AdaptedCurrentModel) else self.base

    def _predict(self, log: InteractionLog) -> np.ndarray:
        return self.correct(log, self.base_model.predict(log))

    def correct(self, log: InteractionLog, base_prediction: Any) -> np.ndarray:
        """The adapted currents of ``log`` given the base model's prediction on it (no new base predict).

        ``predict(log)`` equals ``correct(log, model.base_model.predict(log))``; evaluations
        that score several corrections of one base model on one log use this.

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        InvalidParameterError
            ``log`` is not an InteractionLog or ``base_prediction`` is not ``(len(log), 2)`` finite currents.
        """
        self._check_fitted()
        if not isinstance(log, InteractionLog):
            raise InvalidParameterError(f"log must be an InteractionLog, got {log!r:.80}")
        pred = real_array("base_prediction", base_prediction, ndim=2)
        if pred.shape != (len(log), 2):
            raise InvalidParameterError(f"base_prediction must have shape {(len(log), 2)!r}, got {pred.shape!r}")
        if self.method == "gain":
            out = pred * self.coefficients_[:, 0][None, :]
        elif self.method == "bayes":
            coef, _ = self._bayes_parts()
            out = np.column_stack([pred[:, k] + self._design(log, pred, k) @ coef[k] for k in range(2)])
        else:
            out = np.column_stack([pred[:, k] + self._design(log, pred, k) @ self.coefficients_[k] for k in range(2)])
        return np.maximum(out, 0.0) if self.nonnegative_ else out

    # ------------------------------------------------------------ persistence
    def _params_to_plain(self) -> dict[str, Any]:
        rec = self.base_model.to_record()
        p = self.get_params()
        p["base"] = {"model_class": rec.model_class, "params": rec.params, "state": rec.state,
                     "trained_on": rec.trained_on, "interval": rec.interval}
        return p

    @classmethod
    def _params_from_plain(cls, params: dict[str, Any]) -> dict[str, Any]:
        p = dict(params)
        b = p["base"]
        target = model_class(b["model_class"])  # imports the estimator (torch) only for it
        if target is None:
            raise KeyError(f"unknown base model class {b['model_class']!r:.80}")
        record = ModelRecord(b["model_class"], b["params"], b["state"], trained_on=b.get("trained_on"),
                             interval=b.get("interval"))  # absent in files from before they were recorded
        p["base"] = target.from_record(record, "the adapted model's base")
        if isinstance(p.get("shrink"), bool):  # files from before the choices: True was the evidence shrink
            p["shrink"] = "evidence" if p["shrink"] else "none"
        return p

    def _state(self) -> dict[str, Any]:
        return {"coefficients": np.asarray(self.coefficients_), "adapted_on_s": self.adapted_on_s_,
                "n_samples": self.n_samples_, "nonnegative": self.nonnegative_, "ground": self.ground_,
                "posterior_cov": self.posterior_cov_, "noise_ratio": self.noise_ratio_,
                "shrink": np.asarray(self.shrink_),
                "evidence": None if self.evidence_ is None else np.asarray(self.evidence_)}

    def _load_state(self, state: dict[str, Any]) -> None:
        coef = real_array("coefficients", state["coefficients"], ndim=2)
        if coef.shape != (2, self._n_coefficients[self.method]):
            raise ValueError(f"coefficients of shape {coef.shape!r} do not fit method {self.method!r}")
        self.coefficients_ = coef
        self.adapted_on_s_ = check_real("adapted_on_s", state["adapted_on_s"], low=0.0)
        self.n_samples_ = check_int("n_samples", state["n_samples"], low=0)
        self.nonnegative_ = check_bool("nonnegative", state["nonnegative"])
        ground = state.get("ground")
        self.ground_ = None if ground is None else check_text("ground", ground)
        post = state.get("posterior_cov")
        self.posterior_cov_ = None if post is None else real_array("posterior_cov", post, ndim=3)
        self.noise_ratio_ = check_real("noise_ratio", state.get("noise_ratio", 1.0))
        factors = real_array("shrink", state.get("shrink", np.ones(2)), ndim=1)  # absent before shrink existed
        if factors.shape != (2,) or np.any(factors < 0) or np.any(factors > 1):
            raise ValueError(f"shrink factors must be 2 values in [0, 1], got {factors!r:.80}")
        self.shrink_ = factors
        evidence = state.get("evidence")  # absent in files from before the interval read the prefix
        self.evidence_ = None if evidence is None else real_array("evidence", evidence, ndim=2)
        if self.evidence_ is not None and (self.evidence_.shape != (4, 2) or np.any(self.evidence_[1:] < 0)
                                           or np.any(np.abs(self.evidence_) > _MAX_EVIDENCE)):
            raise ValueError(f"evidence must be (4, 2): the residual charge, then three variances >= 0, each at most "
                             f"{_MAX_EVIDENCE:.0e}; got {self.evidence_!r:.80}")
        if not (math.isfinite(self.noise_ratio_) and self.noise_ratio_ > 0):
            raise ValueError(f"noise_ratio must be finite and > 0, got {self.noise_ratio_!r}")
        if self.method == "bayes" and (self.posterior_cov_ is None or self.posterior_cov_.shape != (2, 8, 8)):
            raise ValueError("a 'bayes' update needs its (2, 8, 8) posterior covariance")
        if self.posterior_cov_ is not None:
            check_covariances("posterior_cov", self.posterior_cov_, MAX_RUN_VARIANCE)
        if self.noise_ratio_ > 1e6:
            raise ValueError(f"noise_ratio {self.noise_ratio_:.3g} is beyond any plausible one (at most 1e6)")
        if not math.isfinite(self.adapted_on_s_):
            raise ValueError("non-finite adapted_on_s")
