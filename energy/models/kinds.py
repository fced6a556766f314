"""Current models by name: the kinds a user can ask for, and a new unfitted model of each."""

from __future__ import annotations

from typing import Any

from terrawatt_base.checks import check_choice
from terrawatt_base.errors import InvalidParameterError

from ..params import robot_spec
from .base import CurrentModel
from .baselines import ConstantCurrentModel, LinearCurrentModel, PhysicsCurrentModel

__all__ = ["CURRENT_MODEL_KINDS", "LEARNED_KINDS", "new_current_model"]

#: Model kinds by name: ``estimator`` (the improved vibration-conditioned estimator, preset
#: ``default``), ``paper`` (the source paper's network, preset ``paper``) and the baselines.
CURRENT_MODEL_KINDS = ("estimator", "paper", "linear", "physics", "constant")
#: The learned kinds (torch): a progress bar, torch threads, a vibration band, an interval from their own ensemble.
LEARNED_KINDS = ("estimator", "paper")

_BASELINES = {"linear": LinearCurrentModel, "physics": PhysicsCurrentModel, "constant": ConstantCurrentModel}
_PRESETS = dict(zip(LEARNED_KINDS, ("default", "paper")))


def new_current_model(
    kind: str, *, seed: int | None = 0, progress: bool = False, n_threads: int | None = None,
    band_hz: tuple[float, float] | None = None, robot: Any = None,
) -> CurrentModel:
    """A new unfitted current model of ``kind`` (one of :data:`CURRENT_MODEL_KINDS`).

    ``seed``, ``progress`` and ``n_threads`` configure the learned models (``estimator``,
    ``paper``, which import torch here); the baselines are deterministic and take none.
    ``band_hz`` (``(low_hz, high_hz)``) replaces the learned models' vibration band
    (``EstimatorConfig.band_hz``); ``None`` keeps their preset's. ``robot`` (a preset name, a
    robot file or a RobotParams, :func:`energy.params.robot_params`) is the physics model's
    robot (default husky); a preset stays a name in the model's file.

    Raises
    ------
    UnknownNameError
        ``kind`` is not one of :data:`CURRENT_MODEL_KINDS` (the message lists them).
    InvalidParameterError
        A bad ``band_hz``, or a ``band_hz`` for a baseline; a ``robot`` for another kind than physics.

    Examples
    --------
    >>> type(new_current_model("linear")).__name__
    'LinearCurrentModel'
    """
    check_choice("kind", kind, CURRENT_MODEL_KINDS)
    if robot is not None:
        if kind != "physics":
            raise InvalidParameterError(f"robot applies to the physics model only, got kind {kind!r}")
        return PhysicsCurrentModel(robot_spec(robot))
    if kind in _BASELINES:
        if band_hz is not None:
            raise InvalidParameterError(f"band_hz applies to the estimator and paper models only, got kind {kind!r}")
        return _BASELINES[kind]()
    # the learned models need torch: imported here, when asked for, so a baseline never imports it
    from .config import estimator_preset
    from .estimator import VibrationCurrentEstimator

    config: Any = _PRESETS[kind]  # a preset's name, kept as a name in saved parameters
    if band_hz is not None:
        config = estimator_preset(config).replace(band_hz=band_hz)
    return VibrationCurrentEstimator(config, seed=seed, progress=progress, n_threads=n_threads)
