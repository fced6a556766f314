"""Current models by name: the kinds a user can ask for, and a new unfitted model of each."""

from __future__ import annotations

import importlib

from terrain.checks import check_choice

from .base import CurrentModel
from .baselines import ConstantCurrentModel, LinearCurrentModel, PhysicsCurrentModel

__all__ = ["CURRENT_MODEL_KINDS", "new_current_model"]

#: Model kinds by name: ``estimator`` (the improved vibration-conditioned estimator, preset
#: ``default``), ``paper`` (the source paper's network, preset ``paper``) and the baselines.
CURRENT_MODEL_KINDS = ("estimator", "paper", "linear", "physics", "constant")

_BASELINES = {"linear": LinearCurrentModel, "physics": PhysicsCurrentModel, "constant": ConstantCurrentModel}
_PRESETS = {"estimator": "default", "paper": "paper"}


def new_current_model(
    kind: str, *, seed: int | None = 0, progress: bool = False, n_threads: int | None = None
) -> CurrentModel:
    """A new unfitted current model of ``kind`` (one of :data:`CURRENT_MODEL_KINDS`).

    ``seed``, ``progress`` and ``n_threads`` configure the learned models (``estimator``,
    ``paper``, which import torch here); the baselines are deterministic and take none.

    Raises
    ------
    UnknownNameError
        ``kind`` is not one of :data:`CURRENT_MODEL_KINDS` (the message lists them).

    Examples
    --------
    >>> type(new_current_model("linear")).__name__
    'LinearCurrentModel'
    """
    check_choice("kind", kind, CURRENT_MODEL_KINDS)
    if kind in _BASELINES:
        return _BASELINES[kind]()
    estimator = importlib.import_module(f"{__package__}.estimator")
    return estimator.VibrationCurrentEstimator(_PRESETS[kind], seed=seed, progress=progress, n_threads=n_threads)
