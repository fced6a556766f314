"""The catalogue of candidate effects: names, lookup, and the candidates that apply to a model and data."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from .effect_base import EFFECT_KINDS, Effect
from .effects_learned import LearnedResidualEffect
from .effects_measurement import (
    MEASUREMENT_CANDIDATES,
    CurrentGainEffect,
    CurrentOffsetEffect,
    IdleCurrentEffect,
    ImuLagEffect,
    RestCurrentEffect,
    TimeLagEffect,
)
from .effects_physics import (
    LAW_CANDIDATES,
    PARAMETER_CANDIDATES,
    PHYSICS_CANDIDATES,
    LateralFrictionEffect,
    MassEffect,
    MotorConstantEffect,
    PhysicsTermEffect,
    QuadraticDragEffect,
    RollingResistanceEffect,
    RotorInertiaEffect,
    SlopeEffect,
    TrackWidthEffect,
)
from .effects_power import ArmatureHeatEffect, ControlPowerEffect, SensorPowerEffect
from .power_data import POWER_EFFECTS

__all__ = ["EFFECTS_CATALOGUE", "NOT_IDENTIFIABLE_FROM_CURRENT", "LEARNED_EFFECT", "effect", "effect_from_spec",
           "check_effect_names", "resolve_effects", "composition_order"]

#: Name of the last-resort learned correction (not part of the default candidates).
LEARNED_EFFECT = "learned_residual"
#: Physics effects that change power but not the drive current: a current log cannot show them; they are
#: the electrical candidates, fitted on battery power (voltage x pack current) when every log carries it.
NOT_IDENTIFIABLE_FROM_CURRENT: tuple[str, ...] = POWER_EFFECTS
#: Every catalogued effect name: physics terms, resistance laws, parameter errors, measurement effects, electrical,
#: learned.
EFFECTS_CATALOGUE: tuple[str, ...] = (PHYSICS_CANDIDATES + LAW_CANDIDATES + PARAMETER_CANDIDATES
                                      + MEASUREMENT_CANDIDATES + NOT_IDENTIFIABLE_FROM_CURRENT + (LEARNED_EFFECT,))

_CLASSES: dict[str, Any] = {
    "slope": SlopeEffect,
    "quadratic_drag": QuadraticDragEffect,
    "mass": MassEffect,
    "track_width": TrackWidthEffect,
    "rolling_resistance": RollingResistanceEffect,
    "lateral_friction": LateralFrictionEffect,
    "motor_constant": MotorConstantEffect,
    "rotor_inertia": RotorInertiaEffect,
    "idle_current": IdleCurrentEffect,
    "rest_current": RestCurrentEffect,
    "current_offset": CurrentOffsetEffect,
    "current_gain": CurrentGainEffect,
    "time_lag": TimeLagEffect,
    "imu_lag": ImuLagEffect,
    "armature_heat": ArmatureHeatEffect,
    "sensor": SensorPowerEffect,
    "control": ControlPowerEffect,
    LEARNED_EFFECT: LearnedResidualEffect,
}


def effect(name: str) -> Effect:
    """A new :class:`Effect` of the catalogue by name.

    Raises
    ------
    UnknownNameError
        ``name`` is not in :data:`EFFECTS_CATALOGUE` (the message lists the names).
    """
    if not isinstance(name, str) or name not in EFFECTS_CATALOGUE:
        raise UnknownNameError(f"effect {name!r:.80} is not in the catalogue; expected one of {list(EFFECTS_CATALOGUE)!r}")
    if name in _CLASSES:
        return _CLASSES[name]()
    return PhysicsTermEffect(name)


def effect_from_spec(spec: Any) -> Effect:
    """Rebuild an effect from :meth:`Effect.spec` (a dict with ``"name"``, plus ``"labels"`` for per-ground ones).

    Raises
    ------
    UnknownNameError
        An unknown name.
    InvalidParameterError
        Not such a dict.
    """
    if not isinstance(spec, dict) or "name" not in spec:
        raise InvalidParameterError(f"an effect spec must be a dict with a 'name', got {spec!r:.80}")
    out = effect(spec["name"])
    if isinstance(out, RollingResistanceEffect):
        labels = spec.get("labels", [])
        if not isinstance(labels, list) or not all(isinstance(g, str) for g in labels):
            raise InvalidParameterError(f"rolling_resistance labels must be a list of str, got {labels!r:.80}")
        out = out.with_labels(labels)
    return out


def check_effect_names(names: Sequence[str], name: str = "effects") -> tuple[str, ...]:
    """Effect names from the catalogue, each once, checked before any work; errors say ``name``.

    Raises
    ------
    UnknownNameError
        A name not in :data:`EFFECTS_CATALOGUE` (the message lists the names).
    InvalidParameterError
        Not a sequence of strings, or a name twice.

    Examples
    --------
    >>> check_effect_names(["inertia", "idle_current"])
    ('inertia', 'idle_current')
    """
    if isinstance(names, str) or not isinstance(names, Sequence) or not all(isinstance(e, str) for e in names):
        raise InvalidParameterError(f"{name} must be a sequence of effect names, got {names!r:.80}")
    bad = [e for e in names if e not in EFFECTS_CATALOGUE]
    if bad:
        raise UnknownNameError(f"{name} {bad!r}: not in the catalogue; expected names from {list(EFFECTS_CATALOGUE)!r}")
    if len(set(names)) != len(names):
        raise InvalidParameterError(f"{name} names an effect twice: {list(names)!r}")
    return tuple(names)


def resolve_effects(effects: Sequence[Any] | None) -> list[Effect]:
    """Candidate effects: names from the catalogue and/or :class:`Effect` objects (None: every catalogued one but the learned).

    Raises
    ------
    UnknownNameError
        A name not in the catalogue.
    InvalidParameterError
        Not a sequence, an entry that is neither a name nor an Effect, duplicates, an
        effect of an unknown kind.
    """
    if effects is None:
        return [effect(n) for n in EFFECTS_CATALOGUE if n != LEARNED_EFFECT]
    if isinstance(effects, (str, Effect)):
        effects = [effects]
    if not isinstance(effects, Sequence) or not effects:
        raise InvalidParameterError(f"effects must be None or a non-empty sequence of effect names, got {effects!r:.80}")
    out: list[Effect] = []
    for e in effects:
        item = e if isinstance(e, Effect) else effect(e)
        if item.kind not in EFFECT_KINDS:
            raise InvalidParameterError(f"effect {item.name!r} has kind {item.kind!r}; expected one of {EFFECT_KINDS!r}")
        out.append(item)
    names = [e.name for e in out]
    if len(set(names)) != len(names):
        raise InvalidParameterError(f"effects has duplicate names: {names!r}")
    return out


def composition_order(effect_: Effect) -> tuple[int, int]:
    """Sort key composing effects onto a prediction: physics, parameters and electrical, learned, then measurement."""
    kind = {"parameter": 0, "physics": 0, "electrical": 0, "learned": 1, "measurement": 2}.get(effect_.kind, 1)
    pos = EFFECTS_CATALOGUE.index(effect_.name) if effect_.name in EFFECTS_CATALOGUE else -1
    return kind, pos
