"""A fitted model applied to logs: its scores, or its predictions where currents are missing (``terrawatt predict``)."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

from terrawatt_base.checks import check_text
from terrawatt_base.errors import InvalidParameterError

from ..logs import InteractionLog
from ..models.base import CurrentModel
from ..prediction import predict_runs
from .results import PREFIT_PROTOCOL, EvaluationResult
from .scoring import score_current_model

__all__ = ["predict_logs"]


def predict_logs(model: CurrentModel, logs: Sequence[InteractionLog], *, label: str = "model") -> EvaluationResult:
    """Apply a fitted model to logs: score it (:func:`score_current_model`) when every log has measured currents,
    else predict each run (:func:`energy.prediction.predict_runs`).

    Parameters
    ----------
    model : CurrentModel
        A fitted model (e.g. :func:`energy.load_current_model`).
    logs : sequence of InteractionLog
    label : str
        How the files name the model (e.g. its file); its last path part names it in the scores.

    Returns
    -------
    EvaluationResult
        Protocol ``"prefit"``: :attr:`~EvaluationResult.scored`, or the predictions only.

    Raises
    ------
    InvalidParameterError
        Not a CurrentModel, no logs, a blank label.
    NotFittedError, DataError
        As ``model.predict``.
    """
    if not isinstance(model, CurrentModel):
        raise InvalidParameterError(f"model must be a CurrentModel, got {type(model).__name__!r}", parameter="model")
    label = check_text("label", label)
    items = [logs] if isinstance(logs, InteractionLog) else list(logs)
    if not items or not all(isinstance(log, InteractionLog) for log in items):
        raise InvalidParameterError("logs must be one InteractionLog or a non-empty sequence of them", parameter="logs")
    if all(log.has_currents for log in items):
        return dataclasses.replace(score_current_model(model, items, name=Path(label).name), label=label)
    return EvaluationResult((), (), protocol=PREFIT_PROTOCOL, models=(Path(label).name,), logs=tuple(items),
                            label=label, model=model, predictions=tuple(predict_runs(model, items)))
