"""Scoring drive-current models on held-out runs: leave-one-run-out folds and their results.

Modules: :mod:`~energy.evaluation.results` (the score records, their summaries and files)
and :mod:`~energy.evaluation.scoring` (:func:`score_run`, the one per-run scoring,
:func:`score_current_model` for a model fitted beforehand, :func:`evaluate_current_models`).
"""

from .results import (
    EVALUATION_FILES,
    EVALUATION_FORMAT_VERSION,
    EVALUATION_VARIANTS,
    PREFIT_VARIANT,
    SCORE_VARIANTS,
    SIDES,
    EvaluationResult,
    RunScore,
    ScoreSummary,
    check_evaluation_dir,
    summarise_scores,
)
from .scoring import evaluate_current_models, run_names, score_current_model, score_run

__all__ = [
    "EVALUATION_VARIANTS",
    "PREFIT_VARIANT",
    "SCORE_VARIANTS",
    "EVALUATION_FORMAT_VERSION",
    "EVALUATION_FILES",
    "SIDES",
    "RunScore",
    "ScoreSummary",
    "EvaluationResult",
    "summarise_scores",
    "check_evaluation_dir",
    "run_names",
    "score_run",
    "score_current_model",
    "evaluate_current_models",
]
