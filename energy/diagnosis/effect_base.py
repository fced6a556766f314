"""The candidate-effect contract of the diagnosis: :class:`EffectParameter` and :class:`Effect`."""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrain.checks import check_real, check_text
from terrain.errors import InvalidParameterError

from .model_currents import PhysicsBasis, physics_basis

__all__ = ["EFFECT_KINDS", "EffectParameter", "Effect", "BasisEffect"]

#: Kinds of candidate effect (``"electrical"``: fitted on battery power, not on the drive currents).
EFFECT_KINDS = ("parameter", "physics", "learned", "measurement", "electrical")


@dataclass(frozen=True)
class EffectParameter:
    """One fitted parameter of an effect: its start value, plausible bounds and unit.

    ``true_name`` names the simulator / physics quantity the parameter estimates, when
    there is one (e.g. ``"mass_kg"``), so a benchmark can compare it with the truth.

    Raises
    ------
    InvalidParameterError
        A blank name or unit, non-finite values, ``low >= high`` or ``initial`` outside
        ``[low, high]``.
    """

    name: str
    initial: float
    low: float
    high: float
    unit: str
    true_name: str | None = None

    def __post_init__(self) -> None:
        own = "EffectParameter"
        check_text("name", self.name, owner=own)
        if not isinstance(self.unit, str):
            raise InvalidParameterError(f"EffectParameter.unit must be a str, got {self.unit!r}")
        low = check_real("low", self.low, owner=own)
        high = check_real("high", self.high, owner=own)
        if not low < high:
            raise InvalidParameterError(f"EffectParameter {self.name!r}: low {low!r} must be below high {high!r}")
        initial = check_real("initial", self.initial, low=low, high=high, owner=own)
        for k, v in (("low", low), ("high", high), ("initial", initial)):
            object.__setattr__(self, k, v)


class Effect:
    """One candidate unmodelled effect: knows its parameters and how to add itself to a prediction.

    Subclasses set :attr:`name`, :attr:`kind` (one of :data:`EFFECT_KINDS`),
    :attr:`parameters` and :attr:`description`, and implement :meth:`prepare` (per-log
    precomputation, vectorised) and :meth:`apply` (the corrected ``(N, 2)`` current for
    parameter values, vectorised). ``predicted_a`` given to :meth:`apply` is the current
    *before* the clamp at 0 of models that clamp (the diagnosis clamps after composing).
    """

    name: str = "effect"
    kind: str = "physics"
    parameters: tuple[EffectParameter, ...] = ()
    description: str = ""

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r}, kind={self.kind!r}, n_parameters={self.n_parameters})"

    @property
    def n_parameters(self) -> int:
        """Number of fitted parameters."""
        return len(self.parameters)

    @property
    def initial(self) -> np.ndarray:
        """Start values of the parameters."""
        return np.array([p.initial for p in self.parameters], dtype=np.float64)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the parameters."""
        return (np.array([p.low for p in self.parameters], dtype=np.float64),
                np.array([p.high for p in self.parameters], dtype=np.float64))

    def applies_to(self, model: Any) -> bool:
        """Whether the effect can be added to ``model`` (False when the model already has it)."""
        return True

    def unsupported(self, logs: Sequence[Any], terrain: Any, model: Any = None) -> str | None:
        """Why the data (or ``model``, the model under test) cannot show this effect (e.g. no
        poses for slope), or None."""
        return None

    def bind(self, logs: Sequence[Any], terrain: Any = None, robot: Any = None) -> Effect:
        """The effect specialised to the data (per-ground parameters, a terrain map, the robot of
        a non-physics model); default itself."""
        return self

    def spec(self) -> dict[str, Any]:
        """Plain description from which :func:`energy.diagnosis.effect_from_spec` rebuilds it."""
        return {"name": self.name}

    def prepare(self, model: Any, log: Any) -> Any:  # pragma: no cover - abstract
        """Per-log precomputation for :meth:`apply` (vectorised)."""
        raise NotImplementedError

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Any) -> np.ndarray:  # pragma: no cover
        """``predicted_a`` (N, 2) with the effect added for parameter ``values``."""
        raise NotImplementedError

    def apply_surrogate(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Any) -> np.ndarray:
        """A cheap approximation of :meth:`apply` used only while fitting (e.g. an interpolated
        table instead of a physics re-prediction); scores and predictions always use
        :meth:`apply`. Default: :meth:`apply` itself."""
        return self.apply(values, predicted_a, prepared)

    def negligible(self, values: np.ndarray) -> bool:
        """Whether fitted ``values`` are below what the data can resolve (never added then); default False."""
        return False

    def penalty(self, values: np.ndarray) -> np.ndarray:
        """Extra least-squares residuals (regularisation); none by default."""
        return np.zeros(0)

    def values_dict(self, values: Any) -> dict[str, float]:
        """Parameter values by name (finite floats)."""
        arr = np.asarray(values, dtype=np.float64).reshape(-1)
        if arr.size != self.n_parameters:
            raise InvalidParameterError(f"effect {self.name!r} has {self.n_parameters} parameters, got {arr.size} values")
        return {p.name: float(v) for p, v in zip(self.parameters, arr) if math.isfinite(v)}


class BasisEffect(Effect):
    """An effect computed from a model's physics basis (:func:`~energy.diagnosis.model_currents.physics_basis`);
    :meth:`bind` keeps the robot given for a model that is not a physics one."""

    robot: Any = None

    def bind(self, logs: Sequence[Any], terrain: Any = None, robot: Any = None) -> Effect:
        out = copy.copy(self)
        out.robot = robot
        return out

    def basis(self, model: Any) -> PhysicsBasis:
        """The physics basis of ``model`` (the bound robot for a model that is not a physics one)."""
        return physics_basis(model, self.robot)
