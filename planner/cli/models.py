"""The current models the command line names (``--model``): name -> a new unfitted model."""

from __future__ import annotations

from typing import Any

from terrain.checks import check_choice

__all__ = ["CURRENT_MODELS", "current_model"]

#: Current models selectable on the command line: estimator (improved default), paper
#: (the source network), and the baselines.
CURRENT_MODELS = ("estimator", "paper", "linear", "physics", "constant")


def current_model(name: str, seed: int, *, progress: bool = False, n_threads: int | None = None) -> Any:
    """A new unfitted current model of kind ``name`` (one of :data:`CURRENT_MODELS`).

    ``seed``, ``progress`` and ``n_threads`` go to the learned models (``estimator``,
    ``paper``); the baselines take none of them.

    Raises
    ------
    UnknownNameError
        ``name`` not one of :data:`CURRENT_MODELS`.
    """
    check_choice("--model", name, CURRENT_MODELS)
    if name in ("estimator", "paper"):
        from energy import VibrationCurrentEstimator

        preset = "default" if name == "estimator" else "paper"
        return VibrationCurrentEstimator(preset, seed=seed, progress=progress, n_threads=n_threads)
    from energy import ConstantCurrentModel, LinearCurrentModel, PhysicsCurrentModel

    return {"linear": LinearCurrentModel, "physics": PhysicsCurrentModel, "constant": ConstantCurrentModel}[name]()
