"""A forecast interval for any current model, cross-validated by refitting it.

The estimator learns its interval while it trains (its cross-validation ensemble). Any other
model — the fitted physics model, the linear or constant baselines, a model of your own —
gets one from :func:`fit_interval`: the model is fitted on every run, then refitted
``folds`` times with a fifth (say) of the runs left out each time, so that every run has an
out-of-fold prediction; with two grounds or more it is also refitted once per ground left
out, for the spread of a ground it never drove. The residuals make its
:class:`~energy.models.uncertainty.IntervalModel`. Cheap models refit in seconds; for the
estimator this costs ``folds + grounds`` trainings, which its own ensemble avoids.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from terrawatt_base.checks import check_int
from terrawatt_base.errors import DataError, InvalidParameterError

from ..logs import InteractionLog
from .base import CurrentModel, check_logs, log_currents
from .uncertainty import IntervalModel

__all__ = ["DEFAULT_INTERVAL_FOLDS", "fit_interval"]

#: Folds of :func:`fit_interval` (runs are dealt round-robin: run ``i`` is left out of fold ``i % folds``).
DEFAULT_INTERVAL_FOLDS = 5


def fit_interval(model: CurrentModel, logs: InteractionLog | Sequence[InteractionLog], *,
                 folds: int = DEFAULT_INTERVAL_FOLDS) -> CurrentModel:
    """Fit ``model`` on ``logs`` and give it a cross-validated forecast interval; returns ``model``.

    Parameters
    ----------
    model : CurrentModel
        An unfitted (or fitted: it is refitted) model whose ``clone()`` makes an equal
        unfitted copy.
    logs : InteractionLog or sequence of InteractionLog
        Training runs, at least 2 (``meta.ground_label`` set on runs of two grounds or more
        for the new-ground spread).
    folds : int
        Refits leaving runs out (>= 2; at most the number of runs).

    Returns
    -------
    CurrentModel
        ``model``, fitted on every run, with ``interval_`` set (``gives_interval`` True).

    Raises
    ------
    InvalidParameterError
        ``model`` is not a CurrentModel (or an adapted one: adapt after calibrating the base),
        bad ``folds``.
    DataError
        Fewer than 2 runs; and as the model's ``fit``.
    """
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a CurrentModel, got {model!r:.80}")
    if type(model).__name__ == "AdaptedCurrentModel":
        raise InvalidParameterError("fit_interval calibrates a base model; adapt it afterwards (the update keeps it)")
    k = check_int("folds", folds, low=2)
    items = check_logs(logs)
    if len(items) < 2:
        raise DataError(f"a cross-validated interval needs at least 2 training runs, got {len(items)}")
    k = min(k, len(items))
    fold_of = np.arange(len(items)) % k
    predictions: list[np.ndarray] = [np.empty(0)] * len(items)
    for f in range(k):
        held = np.flatnonzero(fold_of == f)
        refit = model.clone().fit([lg for i, lg in enumerate(items) if fold_of[i] != f])
        for i in held:
            predictions[i] = refit.predict(items[i])
    residuals = [log_currents(lg) - p for lg, p in zip(items, predictions)]
    by_ground: dict[str, list[tuple[InteractionLog, np.ndarray, np.ndarray]]] = {}
    grounds = list(dict.fromkeys(str(lg.meta.ground_label) for lg in items if lg.meta.ground_label is not None))
    if len(grounds) >= 2:
        for g in grounds:
            without = model.clone().fit([lg for lg in items if str(lg.meta.ground_label) != g])
            pairs = [(lg, without.predict(lg)) for lg in items if str(lg.meta.ground_label) == g]
            by_ground[g] = [(lg, log_currents(lg) - p, p) for lg, p in pairs]
    model.fit(items)
    model.interval_ = IntervalModel.fit(items, residuals, predictions, cross_validated=True,
                                        new_ground_residuals=by_ground)
    return model
