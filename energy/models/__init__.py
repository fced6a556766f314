"""Drive-current models: the contract and its persistence, the baselines and the torch estimator.

Modules: :mod:`~energy.models.base` (the :class:`CurrentModel` contract and its torch-free
file format), :mod:`~energy.models.baselines` (constant, linear, fitted physics),
:mod:`~energy.models.loading` (:func:`load_current_model`), :mod:`~energy.models.kinds` (models by name),
:mod:`~energy.models.training_report` (a model of a kind trained on logs, reported),
:mod:`~energy.models.adaptation` (in-run adaptation of a fitted model), and the torch estimator in three
parts after minGPT: :mod:`~energy.models.net` (the network), :mod:`~energy.models.data`
(the windowed dataset), :mod:`~energy.models.training` (the seeded training loop), plus
:mod:`~energy.models.config` (its configuration and presets) and
:mod:`~energy.models.estimator` (the estimator).

The torch-backed names are loaded on first use (PEP 562), so importing this package, a
baseline or :func:`load_current_model` does not import torch.
"""

from __future__ import annotations

import importlib
from typing import Any

from .adaptation import (
    ADAPT_METHODS,
    ADAPT_SCOPES,
    ADAPT_SHRINKS,
    MIN_ADAPT_SAMPLES,
    MIN_ADAPT_SECONDS,
    AdaptedCurrentModel,
)
from .base import (
    CURRENT_MODEL_FORMAT,
    CURRENT_MODEL_FORMAT_VERSION,
    LEGACY_FORMAT_VERSIONS,
    CurrentModel,
    ModelRecord,
    TrainedOn,
    check_logs,
    log_currents,
    read_model_file,
    write_model_file,
)
from .baselines import (
    PHYSICS_FIT_PARAMETERS,
    ConstantCurrentModel,
    LinearCurrentModel,
    PhysicsCurrentModel,
)
from .calibration import DEFAULT_INTERVAL_FOLDS, fit_interval
from .forecast import ChargeForecast, CurrentForecast
from .kinds import CURRENT_MODEL_KINDS, LEARNED_KINDS, new_current_model
from .loading import MODEL_CLASSES, load_current_model, model_class
from .training_report import (
    TRAINING_FORMAT_VERSION,
    ModelOptions,
    RunCharge,
    TrainingReport,
    check_learned_band,
    check_training_options,
    train_report,
)
from .uncertainty import IntervalModel

#: Names that need torch, by the module that defines them (imported on first access).
TORCH_NAMES: dict[str, str] = {
    "CurrentNet": "net",
    "CurrentNetConfig": "net",
    "SeededDropout": "net",
    "WindowDataset": "data",
    "LOSSES": "training",
    "TrainConfig": "training",
    "TrainingHistory": "training",
    "train_network": "training",
    "train_ensemble": "ensemble",
    "RUN_FEATURES": "config",
    "RESAMPLE_METHODS": "config",
    "EstimatorConfig": "config",
    "ESTIMATOR_PRESETS": "config",
    "estimator_preset": "config",
    "VibrationCurrentEstimator": "estimator",
}


def __getattr__(name: str) -> Any:
    """Import a torch-backed name on first access (PEP 562; ``energy`` uses it too)."""
    module = TORCH_NAMES.get(name)
    if module is None:  # this function also serves ``energy``: name neither package
        raise AttributeError(f"energy has no attribute {name!r} (nor has energy.models)")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


__all__ = [
    "CURRENT_MODEL_FORMAT",
    "CURRENT_MODEL_FORMAT_VERSION",
    "LEGACY_FORMAT_VERSIONS",
    "CurrentModel",
    "ModelRecord",
    "TrainedOn",
    "CurrentForecast",
    "ChargeForecast",
    "IntervalModel",
    "fit_interval",
    "DEFAULT_INTERVAL_FOLDS",
    "check_logs",
    "log_currents",
    "read_model_file",
    "write_model_file",
    "MODEL_CLASSES",
    "model_class",
    "load_current_model",
    "CURRENT_MODEL_KINDS",
    "new_current_model",
    "LEARNED_KINDS",
    "ModelOptions",
    "check_learned_band",
    "check_training_options",
    "TRAINING_FORMAT_VERSION",
    "RunCharge",
    "TrainingReport",
    "train_report",
    "ConstantCurrentModel",
    "LinearCurrentModel",
    "PhysicsCurrentModel",
    "PHYSICS_FIT_PARAMETERS",
    "ADAPT_METHODS",
    "MIN_ADAPT_SECONDS",
    "MIN_ADAPT_SAMPLES",
    "AdaptedCurrentModel",
    "ADAPT_SCOPES",
    "ADAPT_SHRINKS",
    "TORCH_NAMES",
    *TORCH_NAMES,
]

