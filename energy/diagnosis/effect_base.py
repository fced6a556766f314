"""The candidate-effect contract of the diagnosis: :class:`EffectParameter` and :class:`Effect`."""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrawatt_base.checks import check_real, check_text, fmt_number
from terrawatt_base.errors import InvalidParameterError

from .model_currents import PhysicsBasis, physics_basis

__all__ = ["EFFECT_KINDS", "AT_BOUND_FRACTION", "GAIN_PLAUSIBLE", "EffectParameter", "Effect", "BasisEffect"]

#: Kinds of candidate effect (``"electrical"``: fitted on battery power, not on the drive currents).
EFFECT_KINDS = ("parameter", "physics", "learned", "measurement", "electrical")


#: A fitted value within this fraction of its fitting range from a bound is *at* the bound (a bounded
#: least-squares fit stops on it; 1e-3 of a 0-1000 ohm range flagged 0.3 ohm as pinned at 0).
AT_BOUND_FRACTION = 1e-6
#: Plausible range of a gain on a modelled quantity (a physics term, a current sensor): its usual error.
GAIN_PLAUSIBLE = (0.8, 1.25)


@dataclass(frozen=True)
class EffectParameter:
    """One fitted parameter of an effect: its start value, fitting bounds, plausible range and unit.

    ``low`` / ``high`` bound the least-squares fit (wide: a fit should rarely stop there);
    ``plausible_low`` / ``plausible_high`` are the *physical* range a value must lie in to
    be believed (a mass of up to 3 times the robot's, a rolling resistance of 0.005-0.4), by default the fitting bounds, with ``plausible_note`` saying why.
    ``true_name`` names the simulator / physics quantity the parameter estimates, when
    there is one (e.g. ``"mass_kg"``), so a benchmark can compare it with the truth.

    Raises
    ------
    InvalidParameterError
        A blank name or unit, non-finite values, ``low >= high``, ``initial`` outside
        ``[low, high]``, ``plausible_low >= plausible_high``.

    Examples
    --------
    >>> p = EffectParameter("gain", 1.0, 0.0, 3.0, "1", plausible_low=0.8, plausible_high=1.25)
    >>> p.plausible(1.1), p.plausible(2.0), p.at_bound(3.0), EffectParameter("g", 0.0, -1.0, 1.0, "A").plausible_high
    (True, False, 'high', 1.0)
    """

    name: str
    initial: float
    low: float
    high: float
    unit: str
    true_name: str | None = None
    plausible_low: float | None = None
    plausible_high: float | None = None
    plausible_note: str = ""

    def __post_init__(self) -> None:
        own = "EffectParameter"
        check_text("name", self.name, owner=own)
        if not isinstance(self.unit, str):
            raise InvalidParameterError(f"EffectParameter.unit must be a str, got {self.unit!r}")
        if not isinstance(self.plausible_note, str):
            raise InvalidParameterError(f"EffectParameter.plausible_note must be a str, got {self.plausible_note!r}")
        low = check_real("low", self.low, owner=own)
        high = check_real("high", self.high, owner=own)
        if not low < high:
            raise InvalidParameterError(f"EffectParameter {self.name!r}: low {low!r} must be below high {high!r}")
        initial = check_real("initial", self.initial, low=low, high=high, owner=own)
        p_low = low if self.plausible_low is None else check_real("plausible_low", self.plausible_low, owner=own)
        p_high = high if self.plausible_high is None else check_real("plausible_high", self.plausible_high, owner=own)
        if not p_low < p_high:
            raise InvalidParameterError(f"EffectParameter {self.name!r}: plausible_low {p_low!r} must be below "
                                        f"plausible_high {p_high!r}")
        for k, v in (("low", low), ("high", high), ("initial", initial), ("plausible_low", p_low),
                     ("plausible_high", p_high)):
            object.__setattr__(self, k, v)

    def plausible(self, value: float) -> bool:
        """Whether ``value`` lies in ``[plausible_low, plausible_high]``."""
        return bool(self.plausible_low <= float(value) <= self.plausible_high)

    def at_bound(self, value: float) -> str | None:
        """``"low"`` or ``"high"`` when ``value`` sits at that fitting bound (within
        :data:`AT_BOUND_FRACTION` of the range), else None."""
        tol = AT_BOUND_FRACTION * (self.high - self.low)
        if float(value) <= self.low + tol:
            return "low"
        if float(value) >= self.high - tol:
            return "high"
        return None

    def flags(self, value: float) -> tuple[str, ...]:
        """Why a fitted ``value`` is doubtful: outside the plausible range, at a fitting bound (empty when neither)."""
        v = float(value)
        out = []
        if not math.isfinite(v):
            return (f"{self.name} is not finite ({v!r})",)
        unit = "" if self.unit in ("", "1") else f" {self.unit}"
        if not self.plausible(v):
            why = f" ({self.plausible_note})" if self.plausible_note else ""
            out.append(f"{self.name} = {fmt_number(v, 4)}{unit} lies outside its plausible "
                       f"{fmt_number(self.plausible_low, 3)} … {fmt_number(self.plausible_high, 3)}{unit}{why}")
        side = self.at_bound(v)
        if side is not None:
            bound = self.low if side == "low" else self.high
            out.append(f"{self.name} = {fmt_number(v, 4)}{unit} is pinned at its fitting bound "
                       f"{fmt_number(bound, 3)}{unit}: the data ask for a value beyond it")
        return tuple(out)


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
    #: Values of the first parameter a fit scans before it starts (best one first): for a
    #: non-convex parameter such as a lag, whose least-squares fit stops at a kink near its start.
    scan: tuple[float, ...] = ()

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

    def priors(self, prepared: Sequence[Any] = ()) -> np.ndarray:
        """The value of each parameter that changes nothing: the model's own value of a parameter
        the effect re-predicts (mass, rolling resistance, motor constant), 1 for a gain, 0 for an
        offset or a lag. ``prepared``: the effect's per-log :meth:`prepare` output (the model's
        values are read from it); default the start values."""
        return self.initial

    def plausible_ranges(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper ends of the parameters' plausible (physical) ranges."""
        return (np.array([p.plausible_low for p in self.parameters], dtype=np.float64),
                np.array([p.plausible_high for p in self.parameters], dtype=np.float64))

    def plausibility_flags(self, values: Any) -> tuple[str, ...]:
        """Why fitted ``values`` are doubtful (:meth:`EffectParameter.flags` of each), empty when plausible."""
        arr = np.asarray(values, dtype=np.float64).reshape(-1)
        return tuple(f for p, v in zip(self.parameters, arr) for f in p.flags(v))

    def describe(self, values: Any, prepared: Sequence[Any] = ()) -> str:
        """Fitted ``values`` in plain words, e.g. ``"mass +80 kg (x1.8 of the robot's 100 kg)"``."""
        arr = np.asarray(values, dtype=np.float64).reshape(-1)
        parts = [f"{p.name} = {fmt_number(v, 4)}{'' if p.unit in ('', '1') else ' ' + p.unit}"
                 for p, v in zip(self.parameters, arr)]
        return f"{self.name} ({', '.join(parts)})" if parts else self.name

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
