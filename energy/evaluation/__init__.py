"""Scoring drive-current models on held-out runs: leave-one-run-out folds and their results.

Modules: :mod:`~energy.evaluation.results` (the score records, their summary rows and the answer of every protocol,
:class:`EvaluationResult`: its summary, JSON, files and figure)
and :mod:`~energy.evaluation.scoring` (:func:`score_run`, the one per-run scoring,
:func:`score_current_model` for a model fitted beforehand, :func:`evaluate_current_models`);
what the battery pays for a run (both sides through the pack, the interval's coverage) in
:mod:`~energy.evaluation.run_totals`; the ``adapt`` protocol in :mod:`~energy.evaluation.adapt_protocol` (adapt on a held-out run's
first seconds, score the rest), :mod:`~energy.evaluation.few_shot` (adapt on a ground left out
of training) and :mod:`~energy.evaluation.adapt_results` (their scores and rows); models of named kinds evaluated
by one protocol in :mod:`~energy.evaluation.evaluation_report` (:func:`evaluate_kinds`); folds run here or on a dask cluster
(:mod:`terrawatt_base.dask_client`).
"""

from ..logs import run_names
from .adapt_protocol import (
    DEFAULT_ADAPT_SECONDS,
    AdaptSettings,
    adaptation_scores,
    evaluate_adaptation,
    named_models,
    schedule_name,
)
from .adapt_results import (
    ADAPT_FILES,
    ADAPT_FORMAT_VERSION,
    ADAPT_PROTOCOLS,
    TRIGGER_SCHEDULE,
    AdaptRow,
    AdaptScore,
    summarise_adapt_scores,
)
from .evaluation_report import check_adapt_options, check_evaluation_options, evaluate_kinds
from .few_shot import evaluate_few_shot, few_shot_scores
from .prediction_report import predict_logs
from .results import (
    EVALUATION_FILES,
    EVALUATION_FORMAT_VERSION,
    EVALUATION_PROTOCOLS,
    EVALUATION_VARIANTS,
    FIGURES_FOLDER,
    PREDICTIONS_FILE,
    PREDICTIONS_FORMAT_VERSION,
    PREFIT_PROTOCOL,
    PREFIT_VARIANT,
    RELIABILITY_FILE,
    RESULT_PROTOCOLS,
    SCORE_VARIANTS,
    SIDES,
    SPECTRA_FILE,
    EvaluationResult,
    RunScore,
    ScoreRow,
    check_evaluation_dir,
    evaluation_files,
    summarise_scores,
)
from .run_totals import VARIANTS, RunTotal, ScoredRun, pack_energy_j, run_totals, summarise_totals
from .scoring import evaluate_current_models, score_current_model, score_run, trim_to_overlap

__all__ = [
    "EVALUATION_PROTOCOLS",
    "EVALUATION_VARIANTS",
    "PREFIT_VARIANT",
    "SCORE_VARIANTS",
    "EVALUATION_FORMAT_VERSION",
    "EVALUATION_FILES",
    "SPECTRA_FILE",
    "RELIABILITY_FILE",
    "SIDES",
    "RunScore",
    "ScoreRow",
    "EvaluationResult",
    "summarise_scores",
    "evaluation_files",
    "check_evaluation_dir",
    "run_names",
    "score_run",
    "score_current_model",
    "evaluate_current_models",
    "trim_to_overlap",
    "ADAPT_PROTOCOLS",
    "ADAPT_FILES",
    "ADAPT_FORMAT_VERSION",
    "TRIGGER_SCHEDULE",
    "DEFAULT_ADAPT_SECONDS",
    "AdaptScore",
    "AdaptRow",
    "AdaptSettings",
    "summarise_adapt_scores",
    "adaptation_scores",
    "schedule_name",
    "named_models",
    "evaluate_adaptation",
    "few_shot_scores",
    "evaluate_few_shot",
    "PREFIT_PROTOCOL",
    "RESULT_PROTOCOLS",
    "PREDICTIONS_FILE",
    "PREDICTIONS_FORMAT_VERSION",
    "FIGURES_FOLDER",
    "predict_logs",
    "RunTotal",
    "ScoredRun",
    "VARIANTS",
    "pack_energy_j",
    "run_totals",
    "summarise_totals",
    "check_adapt_options",
    "check_evaluation_options",
    "evaluate_kinds",
]
