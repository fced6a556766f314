"""Physics candidates: effects the model under test has switched off, and errors of its parameters."""

from __future__ import annotations

import copy
from collections.abc import Sequence
from typing import Any

import numpy as np

from terrain.errors import DataError
from terrain.terrain_map import TerrainMap

from ..logs import InteractionLog
from ..models.baselines import PhysicsCurrentModel
from .effect_base import Effect, EffectParameter
from .model_currents import PhysicsBasis, motoring_currents_a, physics_basis

__all__ = ["PHYSICS_CANDIDATES", "PARAMETER_CANDIDATES", "PhysicsTermEffect", "SlopeEffect", "MassEffect",
           "TrackWidthEffect", "RollingResistanceEffect", "MotorConstantEffect", "log_ground_labels"]

#: Physics effects offered as candidates (those that change the motor current).
PHYSICS_CANDIDATES: tuple[str, ...] = (
    "slope", "inertia", "static_friction", "coulomb_friction", "stribeck", "viscous_friction",
    "longitudinal_slip", "lateral_slip", "turning_resistance", "gear_losses", "torque_saturation",
    "speed_saturation",
)
#: Parameter-error candidates of a physics model.
PARAMETER_CANDIDATES: tuple[str, ...] = ("mass", "track_width", "rolling_resistance", "motor_constant")

_GAIN = EffectParameter("gain", 1.0, 0.0, 3.0, "1", None)


def _is_physics(model: Any) -> bool:
    return isinstance(model, PhysicsCurrentModel) and model.is_fitted


class _BasisEffect(Effect):
    """An effect computed from a model's physics basis (the robot of a non-physics model is bound)."""

    robot: Any = None

    def bind(self, logs: Sequence[Any], terrain: Any = None, robot: Any = None) -> Effect:
        out = copy.copy(self)
        out.robot = robot
        return out

    def basis(self, model: Any) -> PhysicsBasis:
        return physics_basis(model, self.robot)


class PhysicsTermEffect(_BasisEffect):
    """A physics effect the model lacks, as a gain on its current: ``I + gain * (I_with - I_without)``.

    For a :class:`~energy.PhysicsCurrentModel` the term is computed with the model's fitted
    robot and ground; for any other model from the reference physics of the robot.
    """

    kind = "physics"
    parameters = (_GAIN,)

    def __init__(self, effect_name: str) -> None:
        self.name = effect_name
        self.description = f"physics effect {effect_name!r} (gain on its current)"

    def applies_to(self, model: Any) -> bool:
        return not _is_physics(model) or self.name not in model.effects_

    def prepare(self, model: Any, log: InteractionLog) -> np.ndarray:
        b = self.basis(model)
        if b.is_model:
            on, off = tuple(b.effects) + (self.name,), tuple(b.effects)
        else:
            on, off = tuple(b.effects), tuple(e for e in b.effects if e != self.name)
        return motoring_currents_a(b, log, effects=on) - motoring_currents_a(b, log, effects=off)

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        return predicted_a + values[0] * prepared


def log_slope_rad(terrain: TerrainMap, log: InteractionLog) -> np.ndarray:
    """Pitch along the heading at each pose of ``log`` on ``terrain`` (as the truth simulator drives)."""
    pose = log.pose_xyh
    x, y, h = pose[:, 0], pose[:, 1], pose[:, 2]
    gx = np.asarray(terrain.sample("grad_x", x, y, method="bilinear"), dtype=np.float64)
    gy = np.asarray(terrain.sample("grad_y", x, y, method="bilinear"), dtype=np.float64)
    return np.arctan(gx * np.cos(h) + gy * np.sin(h))


class SlopeEffect(_BasisEffect):
    """Gravity along the slope (pitch from the map under the logged poses), as a gain on its current.

    The current models take level ground; this term needs ``terrain`` and poses in every log.
    """

    name = "slope"
    kind = "physics"
    parameters = (_GAIN,)
    description = "slope: gravity along the pitch under the logged poses (needs a map)"
    terrain: Any = None

    def unsupported(self, logs: Sequence[Any], terrain: Any) -> str | None:
        if not isinstance(terrain, TerrainMap):
            return "needs a terrain map (terrain=)"
        if any(log.pose_xyh is None for log in logs):
            return "needs poses in every log"
        return None

    def bind(self, logs: Sequence[Any], terrain: Any = None, robot: Any = None) -> Effect:
        out = super().bind(logs, terrain, robot)
        out.terrain = terrain
        return out

    def prepare(self, model: Any, log: InteractionLog) -> np.ndarray:
        if self.terrain is None or log.pose_xyh is None:
            raise DataError("the slope effect needs a terrain map and poses in the log; bind it to a map first")
        b = self.basis(model)
        slope = log_slope_rad(self.terrain, log)
        on = tuple(dict.fromkeys(tuple(b.effects) + ("slope",)))
        return motoring_currents_a(b, log, effects=on, slope_rad=slope) - motoring_currents_a(b, log)

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        return predicted_a + values[0] * prepared


class _RepredictEffect(_BasisEffect):
    """A parameter error of a physics model: re-predict the physics with the changed value."""

    kind = "parameter"

    def applies_to(self, model: Any) -> bool:
        return _is_physics(model)

    def prepare(self, model: Any, log: InteractionLog) -> tuple[PhysicsBasis, InteractionLog, np.ndarray]:
        b = self.basis(model)
        return b, log, motoring_currents_a(b, log)

    def changed(self, values: np.ndarray, prepared: Any) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Any) -> np.ndarray:
        return predicted_a + self.changed(values, prepared) - prepared[2]


class MassEffect(_RepredictEffect):
    """A mass (payload) error: the physics re-predicted with ``mass_kg * mass_scale``."""

    name = "mass"
    parameters = (EffectParameter("mass_scale", 1.0, 0.5, 2.0, "1", "mass_kg"),)
    description = "mass / payload error (scale on the robot's mass)"

    def changed(self, values: np.ndarray, prepared: Any) -> np.ndarray:
        b, log, _ = prepared
        return motoring_currents_a(b, log, robot=b.robot.replace(mass_kg=b.robot.mass_kg * float(values[0])))


class TrackWidthEffect(_RepredictEffect):
    """An error of the effective skid-steer track width (``track_width_multiplier``)."""

    name = "track_width"
    parameters = (EffectParameter("track_width_multiplier", 1.5, 1.0, 5.0, "1", "track_width_multiplier"),)
    description = "effective track width of skid steering (ICR multiplier)"

    def applies_to(self, model: Any) -> bool:
        return _is_physics(model) and "track_width_multiplier" not in model.fitted_

    def changed(self, values: np.ndarray, prepared: Any) -> np.ndarray:
        b, log, _ = prepared
        return motoring_currents_a(b, log, robot=b.robot.replace(track_width_multiplier=float(values[0])))


def log_ground_labels(log: InteractionLog) -> np.ndarray | None:
    """Per-sample ground labels of a log (its ``ground`` or its run label), or None."""
    if log.ground is not None:
        return np.asarray(log.ground).astype(str)
    if log.meta.ground_label is not None:
        return np.full(len(log), log.meta.ground_label)
    return None


class RollingResistanceEffect(_RepredictEffect):
    """Per-ground rolling resistance: one coefficient per ground label seen in the logs."""

    name = "rolling_resistance"
    parameters: tuple[EffectParameter, ...] = ()
    description = "per-ground rolling-resistance coefficients"
    labels: tuple[str, ...] = ()

    def applies_to(self, model: Any) -> bool:
        return _is_physics(model) and "coulomb_friction" in model.effects_

    def unsupported(self, logs: Sequence[Any], terrain: Any) -> str | None:
        if any(log_ground_labels(log) is None for log in logs):
            return "needs ground labels in every log"
        return None

    def bind(self, logs: Sequence[Any], terrain: Any = None, robot: Any = None) -> Effect:
        out = super().bind(logs, terrain, robot)
        if not logs:  # rebinding a loaded effect: keep its labels
            return out
        found = [log_ground_labels(log) for log in logs]
        out.labels = tuple(sorted({str(x) for lab in found if lab is not None for x in np.unique(lab)}))
        out.parameters = tuple(EffectParameter(f"rolling_resistance_coef_{g}", 0.02, 0.0, 1.0, "1",
                                               f"{g}.rolling_resistance_coef") for g in out.labels)
        return out

    def with_labels(self, labels: Sequence[str]) -> RollingResistanceEffect:
        """The effect for these ground labels (used when loading a corrected model)."""
        out = RollingResistanceEffect()
        out.labels = tuple(str(g) for g in labels)
        out.parameters = tuple(EffectParameter(f"rolling_resistance_coef_{g}", 0.02, 0.0, 1.0, "1",
                                               f"{g}.rolling_resistance_coef") for g in out.labels)
        return out

    def spec(self) -> dict[str, Any]:
        return {"name": self.name, "labels": list(self.labels)}

    def prepare(self, model: Any, log: InteractionLog) -> Any:
        b, lg, base = super().prepare(model, log)
        lab = log_ground_labels(log)
        lookup = {g: k for k, g in enumerate(self.labels)}
        idx = np.array([lookup.get(str(x), len(self.labels)) for x in (lab if lab is not None else [])], dtype=np.intp)
        if idx.size != len(log):
            idx = np.full(len(log), len(self.labels), dtype=np.intp)
        return b, lg, base, idx

    def changed(self, values: np.ndarray, prepared: Any) -> np.ndarray:
        b, log, _, idx = prepared
        grounds = [b.ground.replace(rolling_resistance_coef=float(v)) for v in values] + [b.ground]
        return motoring_currents_a(b, log, ground=grounds, ground_index=idx)


class MotorConstantEffect(_RepredictEffect):
    """A motor-constant error: the motoring current divided by ``torque_constant_scale``."""

    name = "motor_constant"
    parameters = (EffectParameter("torque_constant_scale", 1.0, 0.5, 2.0, "1", "torque_constant_nm_per_a"),)
    description = "motor torque-constant error (scale on Kt)"

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Any) -> np.ndarray:
        return predicted_a + prepared[2] * (1.0 / float(values[0]) - 1.0)
