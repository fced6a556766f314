"""Physics candidates: effects the model under test has switched off, and errors of its parameters."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrain.terrain_map import TerrainMap
from terrawatt_base.checks import fmt_number
from terrawatt_base.errors import DataError

from ..logs import InteractionLog, log_slope_rad, rest_samples
from ..models.baselines import PhysicsCurrentModel
from .effect_base import GAIN_PLAUSIBLE, BasisEffect, Effect, EffectParameter
from .model_currents import ParameterTable, PhysicsBasis, motoring_currents_a, side_speeds_mps

__all__ = ["PHYSICS_CANDIDATES", "BREAKAWAY_EFFECTS", "LAW_CANDIDATES", "PARAMETER_CANDIDATES", "ROLLING_RESISTANCE_PLAUSIBLE",
           "PhysicsTermEffect", "SlopeEffect", "QuadraticDragEffect", "MassEffect", "TrackWidthEffect",
           "RollingResistanceEffect", "LateralFrictionEffect", "MotorConstantEffect", "RotorInertiaEffect", "Reprediction"]

#: Physics effects offered as candidates (those that change the motor current).
PHYSICS_CANDIDATES: tuple[str, ...] = (
    "slope", "inertia", "static_friction", "coulomb_friction", "stribeck", "viscous_friction",
    "longitudinal_slip", "lateral_slip", "turning_resistance", "gear_losses", "torque_saturation",
    "speed_saturation",
)
#: Physics effects whose current lives at the still sample before a start (the breakaway): their candidates
#: are judged there too (:func:`~energy.diagnosis.model_currents.motoring_currents_a`).
BREAKAWAY_EFFECTS: tuple[str, ...] = ("static_friction",)
#: Resistance laws the physics does not hold, offered as candidates with their own coefficient.
LAW_CANDIDATES: tuple[str, ...] = ("quadratic_drag",)
#: Parameter-error candidates of a physics model.
PARAMETER_CANDIDATES: tuple[str, ...] = ("mass", "track_width", "rolling_resistance", "lateral_friction",
                                         "motor_constant", "rotor_inertia")

_GAIN = EffectParameter("gain", 1.0, 0.0, 3.0, "1", None, *GAIN_PLAUSIBLE,
                        "the physics' own term, within the usual error of its parameters")
#: Plausible rolling-resistance coefficients, hard to soft ground.
ROLLING_RESISTANCE_PLAUSIBLE = (0.005, 0.4)


def _is_physics(model: Any) -> bool:
    return isinstance(model, PhysicsCurrentModel) and model.is_fitted


class PhysicsTermEffect(BasisEffect):
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
        starts = self.name in BREAKAWAY_EFFECTS  # the breakaway is judged where it lives: a start
        return (motoring_currents_a(b, log, effects=on, starts=starts)
                - motoring_currents_a(b, log, effects=off, starts=starts))

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        return predicted_a + values[0] * prepared


class SlopeEffect(BasisEffect):
    """Gravity along the slope (pitch from the map under the logged poses), as a gain on its current.

    The current models take level ground; this term needs ``terrain`` and poses in every log.
    """

    name = "slope"
    kind = "physics"
    parameters = (_GAIN,)
    description = "slope: gravity along the pitch under the logged poses (needs a map)"
    terrain: Any = None

    def applies_to(self, model: Any) -> bool:
        # a physics model given the map already drives the slope under its poses
        return not (_is_physics(model) and model.terrain is not None)

    def unsupported(self, logs: Sequence[Any], terrain: Any, model: Any = None) -> str | None:
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


class QuadraticDragEffect(BasisEffect):
    """A resistance growing with the square of the speed: a drag force ``c v_s |v_s|`` on each side s.

    Air drag, or loose ground (sand, mud, deep snow, tall grass) whose resistance rises with the
    speed; the physics' viscous term grows with ``v``, its rolling resistance not at all. The
    motor delivers it through the gear, so each side's current in the direction of rotation grows
    by ``c v_s^2 r / (N_g eta K_t)`` (``eta`` the gear efficiency where the model has gear losses,
    else 1), 0 where the log stands still. Linear in ``c`` (N s^2 / m^2 per side: the force in N at
    1 m/s); the side speeds are :func:`~energy.diagnosis.model_currents.side_speeds_mps`.
    """

    name = "quadratic_drag"
    kind = "physics"
    parameters = (EffectParameter("drag_coef_n_s2_per_m2", 1.0, 0.0, 400.0, "N s^2/m^2", None, 0.0, 100.0,
                                  "per side: air drag well below 1, loose ground rising with speed up to tens"),)
    description = "speed-squared resistance per side (air drag, loose ground): F = c v|v|"

    def prepare(self, model: Any, log: InteractionLog) -> np.ndarray:
        b = self.basis(model)
        motor = b.robot.motor
        eta = motor.gear_efficiency if "gear_losses" in b.effects else 1.0
        per_coef = side_speeds_mps(b, log) ** 2 * b.robot.wheel_radius_m / (motor.gear_ratio * eta
                                                                            * motor.torque_constant_nm_per_a)
        return np.where(rest_samples(log)[:, None], 0.0, per_coef)

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: np.ndarray) -> np.ndarray:
        return predicted_a + values[0] * prepared

    def priors(self, prepared: Sequence[Any] = ()) -> np.ndarray:
        """No drag (the fit starts off the bound, at 1 N s^2/m^2: a least-squares start on it does not move)."""
        return np.zeros(1)

    def describe(self, values: Any, prepared: Sequence[Any] = ()) -> str:
        c = float(np.asarray(values, dtype=np.float64).reshape(-1)[0])
        return (f"speed-squared drag {fmt_number(c, 3)} N s^2/m^2 per side ({fmt_number(c, 3)} N per side at 1 m/s, "
                f"{fmt_number(0.25 * c, 3)} N at 0.5 m/s: air drag or loose ground)")


@dataclass(frozen=True, eq=False)
class Reprediction:
    """Per-log preparation of a parameter-error effect: the basis, the log, the motoring currents
    at the model's values, the per-sample parameter slot (per-ground effects) and the fitting table."""

    basis: PhysicsBasis
    log: InteractionLog
    base_a: np.ndarray
    index: np.ndarray | None
    table: ParameterTable | None


class _RepredictEffect(BasisEffect):
    """A parameter error of a physics model: re-predict the physics with the changed value.

    :meth:`apply` re-predicts exactly (scores, predictions); :meth:`apply_surrogate`, used
    while fitting, interpolates a :class:`ParameterTable` of the physics precomputed at nodes
    of the parameter, so a least-squares fit does not rerun the physics at every evaluation.
    """

    kind = "parameter"

    def applies_to(self, model: Any) -> bool:
        return _is_physics(model)

    def nominal(self, b: PhysicsBasis) -> float:  # pragma: no cover - abstract
        """The parameter's value in the model under test."""
        raise NotImplementedError

    def repredict(self, b: PhysicsBasis, log: InteractionLog, value: float, index: Any = None) -> np.ndarray:
        """Exact motoring currents (N, 2) with every slot of the parameter at ``value``."""
        raise NotImplementedError  # pragma: no cover - abstract

    def index(self, log: InteractionLog) -> np.ndarray | None:
        """Per-sample parameter slot (None: one parameter for every sample)."""
        return None

    def priors(self, prepared: Sequence[Any] = ()) -> np.ndarray:
        """The model's own value of the parameter (every slot), read from the preparation's basis."""
        if prepared and isinstance(prepared[0], Reprediction):
            return np.full(self.n_parameters, float(self.nominal(prepared[0].basis)))
        return self.initial

    def prepare(self, model: Any, log: InteractionLog) -> Reprediction:
        b = self.basis(model)
        idx = self.index(log)
        p = self.parameters[0] if self.parameters else None
        table = None if p is None else ParameterTable(lambda x: self.repredict(b, log, x, idx), p.low, p.high,
                                                       self.nominal(b), slots=idx)
        return Reprediction(b, log, motoring_currents_a(b, log), idx, table)

    def changed(self, values: np.ndarray, prepared: Reprediction) -> np.ndarray:
        """Exact motoring currents (N, 2) at parameter ``values``."""
        return self.repredict(prepared.basis, prepared.log, float(values[0]), prepared.index)

    def per_sample(self, values: np.ndarray, prepared: Reprediction) -> Any:
        """The parameter value of each sample (a scalar when one value holds for every sample)."""
        return float(values[0])

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Reprediction) -> np.ndarray:
        return predicted_a + self.changed(values, prepared) - prepared.base_a

    def apply_surrogate(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Reprediction) -> np.ndarray:
        """:meth:`apply` through the interpolated table (for fitting only)."""
        if prepared.table is None:
            return self.apply(values, predicted_a, prepared)
        return predicted_a + prepared.table.at(self.per_sample(values, prepared)) - prepared.base_a


class MassEffect(_RepredictEffect):
    """A mass (payload) error: the physics re-predicted with ``mass_kg * mass_scale``."""

    name = "mass"
    parameters = (EffectParameter("mass_scale", 1.0, 0.25, 4.0, "1", "mass_kg", 0.5, 3.0,
                                  "0.5x-3x the robot's mass: a payload up to twice its own, not another robot"),)
    description = "mass / payload error (scale on the robot's mass)"

    def nominal(self, b: PhysicsBasis) -> float:
        return 1.0

    def describe(self, values: Any, prepared: Sequence[Any] = ()) -> str:
        scale = float(np.asarray(values, dtype=np.float64).reshape(-1)[0])
        if not prepared or not isinstance(prepared[0], Reprediction):
            return f"mass x{fmt_number(scale, 3)}"
        mass = float(prepared[0].basis.robot.mass_kg)
        change = mass * (scale - 1.0)
        return (f"mass {'+' if change >= 0 else '-'}{fmt_number(abs(change), 3)} kg (x{fmt_number(scale, 3)} of the "
                f"robot's {fmt_number(mass, 4)} kg)")

    def repredict(self, b: PhysicsBasis, log: InteractionLog, value: float, index: Any = None) -> np.ndarray:
        return motoring_currents_a(b, log, robot=b.robot.replace(mass_kg=b.robot.mass_kg * value))


class TrackWidthEffect(_RepredictEffect):
    """An error of the effective skid-steer track width (``track_width_multiplier``)."""

    name = "track_width"
    parameters = (EffectParameter("track_width_multiplier", 1.5, 1.0, 5.0, "1", "track_width_multiplier", 1.0, 3.0,
                                  "skid steering turns about an effective track of 1-3x the geometric one"),)
    description = "effective track width of skid steering (ICR multiplier)"

    def applies_to(self, model: Any) -> bool:
        return _is_physics(model) and "track_width_multiplier" not in model.fitted_

    def unsupported(self, logs: Sequence[Any], terrain: Any, model: Any = None) -> str | None:
        # the rule of measured_side_speeds, read from the logs alone (the model's robot is not known
        # here): a logged track narrower than the robot's geometric one would leave the multiplier free
        if logs and all(log.meta.velocity_source == "measured" and log.meta.track_width_m is not None for log in logs):
            return ("the side speeds are measured wheel speeds (omega derived with meta.track_width_m), "
                    "so the effective track width does not change the predicted current")
        return None

    def nominal(self, b: PhysicsBasis) -> float:
        return float(b.robot.track_width_multiplier)

    def repredict(self, b: PhysicsBasis, log: InteractionLog, value: float, index: Any = None) -> np.ndarray:
        return motoring_currents_a(b, log, robot=b.robot.replace(track_width_multiplier=value))


class LateralFrictionEffect(_RepredictEffect):
    """An error of the lateral friction coefficient of the model's skid-steer turning resistance.

    Offered to a physics model that has ``turning_resistance`` (without it the coefficient
    does nothing; the ``turning_resistance`` candidate then adds the term itself): the
    turning moment of a model whose term is right in form but wrong in size.
    """

    name = "lateral_friction"
    parameters = (EffectParameter("lateral_friction_coef", 0.5, 0.0, 2.0, "1", "lateral_friction_coef", 0.1, 1.0,
                                  "sliding friction of wheels or tracks: ice ~0.1 to rubber on concrete ~1"),)
    description = "lateral friction coefficient of skid-steer turning (the model's turning resistance re-sized)"

    def applies_to(self, model: Any) -> bool:
        return _is_physics(model) and "turning_resistance" in model.effects_

    def nominal(self, b: PhysicsBasis) -> float:
        return float(np.mean([g.effective_lateral_friction_coef for g in b.grounds()]))

    def repredict(self, b: PhysicsBasis, log: InteractionLog, value: float, index: Any = None) -> np.ndarray:
        return motoring_currents_a(b, log, ground=b.replace_grounds(lateral_friction_coef=value))


def _rolling_parameters(labels: Sequence[str]) -> tuple[EffectParameter, ...]:
    return tuple(EffectParameter(f"rolling_resistance_coef_{g}", 0.02, 0.0, 1.0, "1", f"{g}.rolling_resistance_coef",
                                 *ROLLING_RESISTANCE_PLAUSIBLE, "wheels or tracks on ground, hard to soft")
                 for g in labels)


class RollingResistanceEffect(_RepredictEffect):
    """Per-ground rolling resistance: one coefficient per ground label seen in the logs.

    For a model with Coulomb friction, an error of its coefficient on each ground. For a
    model without it, Coulomb (rolling) friction switched on with one coefficient per
    ground — offered only when the logs hold at least two grounds (with one ground it is the
    ``coulomb_friction`` candidate itself, as a coefficient instead of a gain).
    """

    name = "rolling_resistance"
    parameters: tuple[EffectParameter, ...] = ()
    description = "per-ground rolling-resistance coefficients (Coulomb friction switched on if the model lacks it)"
    labels: tuple[str, ...] = ()

    def applies_to(self, model: Any) -> bool:
        return _is_physics(model)

    def unsupported(self, logs: Sequence[Any], terrain: Any, model: Any = None) -> str | None:
        found = [log.ground_labels for log in logs]
        if any(lab is None for lab in found):
            return "needs ground labels in every log"
        n_grounds = len({str(x) for lab in found if lab is not None for x in np.unique(lab)})
        if n_grounds < 2 and _is_physics(model) and "coulomb_friction" not in model.effects_:
            return "one ground and no Coulomb friction in the model: that is the coulomb_friction candidate"
        return None

    def bind(self, logs: Sequence[Any], terrain: Any = None, robot: Any = None) -> Effect:
        out = super().bind(logs, terrain, robot)
        if not logs:  # rebinding a loaded effect: keep its labels
            return out
        found = [log.ground_labels for log in logs]
        out.labels = tuple(sorted({str(x) for lab in found if lab is not None for x in np.unique(lab)}))
        out.parameters = _rolling_parameters(out.labels)
        return out

    def with_labels(self, labels: Sequence[str]) -> RollingResistanceEffect:
        """The effect for these ground labels (used when loading a corrected model)."""
        out = RollingResistanceEffect()
        out.labels = tuple(str(g) for g in labels)
        out.parameters = _rolling_parameters(out.labels)
        return out

    def spec(self) -> dict[str, Any]:
        return {"name": self.name, "labels": list(self.labels)}

    @staticmethod
    def _switched_on(b: PhysicsBasis) -> bool:
        return "coulomb_friction" not in b.effects

    def nominal(self, b: PhysicsBasis) -> float:
        return 0.0 if self._switched_on(b) else float(np.mean([g.rolling_resistance_coef for g in b.grounds()]))

    def index(self, log: InteractionLog) -> np.ndarray:
        lab = log.ground_labels
        if lab is None:  # unlisted: the slot after the labels
            return np.full(len(log), len(self.labels), dtype=np.intp)
        found, inverse = np.unique(np.asarray(lab).astype(str), return_inverse=True)
        lookup = {g: k for k, g in enumerate(self.labels)}
        return np.array([lookup.get(g, len(self.labels)) for g in found.tolist()], dtype=np.intp)[inverse]

    def _grounds(self, b: PhysicsBasis, values: Sequence[float]) -> list[Any]:
        # samples of grounds not listed keep the model's physics: its coefficient, or none when
        # Coulomb friction is switched on here
        # (a model with a ground per label has each listed label's own ground; it refuses unknown labels)
        own = [b.ground.get(g, b.grounds()[0]) if isinstance(b.ground, dict) else b.ground for g in self.labels]
        first = own[0] if own else b.grounds()[0]
        other = first.replace(rolling_resistance_coef=0.0) if self._switched_on(b) else first
        return [g.replace(rolling_resistance_coef=float(v)) for g, v in zip(own, values)] + [other]

    def _currents(self, b: PhysicsBasis, log: InteractionLog, grounds: list[Any], index: Any) -> np.ndarray:
        effects = tuple(b.effects) + ("coulomb_friction",) if self._switched_on(b) else None
        return motoring_currents_a(b, log, effects=effects, ground=grounds, ground_index=index)

    def repredict(self, b: PhysicsBasis, log: InteractionLog, value: float, index: Any = None) -> np.ndarray:
        return self._currents(b, log, self._grounds(b, [value] * len(self.labels)), index)

    def changed(self, values: np.ndarray, prepared: Reprediction) -> np.ndarray:
        b = prepared.basis
        return self._currents(b, prepared.log, self._grounds(b, values), prepared.index)

    def per_sample(self, values: np.ndarray, prepared: Reprediction) -> np.ndarray:
        # samples of unlisted grounds keep the model's ground whatever the value: any value will do
        return np.append(np.asarray(values, dtype=np.float64), prepared.table.nodes[0])[prepared.index]

    def apply_surrogate(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Reprediction) -> np.ndarray:
        """:meth:`apply` through the table, one interpolation per ground (for fitting only)."""
        if prepared.table is None:
            return self.apply(values, predicted_a, prepared)
        slots = np.append(np.asarray(values, dtype=np.float64), prepared.table.nodes[0])
        return predicted_a + prepared.table.at_slots(slots) - prepared.base_a


class MotorConstantEffect(_RepredictEffect):
    """A motor-constant error: the motoring current divided by ``torque_constant_scale``."""

    name = "motor_constant"
    parameters = (EffectParameter("torque_constant_scale", 1.0, 0.5, 2.0, "1", "torque_constant_nm_per_a", 0.8, 1.25,
                                  "a motor's constant strays by some per cent from its rating, with heat"),)
    description = "motor torque-constant error (scale on Kt)"

    def nominal(self, b: PhysicsBasis) -> float:
        return 1.0

    def prepare(self, model: Any, log: InteractionLog) -> Reprediction:
        b = self.basis(model)
        return Reprediction(b, log, motoring_currents_a(b, log), None, None)  # analytic: no table

    def apply(self, values: np.ndarray, predicted_a: np.ndarray, prepared: Reprediction) -> np.ndarray:
        return predicted_a + prepared.base_a * (1.0 / float(values[0]) - 1.0)


class RotorInertiaEffect(_RepredictEffect):
    """A drivetrain-inertia error: the physics re-predicted with the motor's rotor inertia ``Jm`` times
    ``rotor_inertia_scale``.

    The rotating parts (rotor, gearbox, wheels or tracks, referred to the motor shaft) add
    ``Jm N_g a_side / (r K_t)`` to each side's current: a current in proportion to that side's
    wheel acceleration, apart from the body's ``m a / 2`` (which the ``mass`` candidate scales
    along with every other mass term). Offered to a physics model that has ``inertia`` switched
    on and a rotor inertia to scale (without the term, the ``inertia`` candidate adds it whole).
    The fitted value is reported in kg m^2 at the motor shaft and as the rotating mass it adds per
    side at the wheels, ``Jm N_g^2 / r^2``.
    """

    name = "rotor_inertia"
    parameters = (EffectParameter("rotor_inertia_scale", 1.0, 0.0, 20.0, "1", "rotor_inertia_kg_m2", 0.2, 10.0,
                                  "the motor's rotor alone, up to ten times it with the gearbox and the wheels or "
                                  "tracks referred to the motor shaft"),)
    description = "rotor / drivetrain inertia error (scale on the motor's rotor inertia Jm)"

    def applies_to(self, model: Any) -> bool:
        return (_is_physics(model) and "inertia" in model.effects_
                and float(model.robot_.motor.rotor_inertia_kg_m2) > 0.0)

    def nominal(self, b: PhysicsBasis) -> float:
        return 1.0

    def describe(self, values: Any, prepared: Sequence[Any] = ()) -> str:
        scale = float(np.asarray(values, dtype=np.float64).reshape(-1)[0])
        if not prepared or not isinstance(prepared[0], Reprediction):
            return f"rotor inertia x{fmt_number(scale, 3)}"
        rb = prepared[0].basis.robot
        jm = float(rb.motor.rotor_inertia_kg_m2)
        change = jm * (scale - 1.0) * rb.motor.gear_ratio ** 2 / rb.wheel_radius_m ** 2
        return (f"rotor inertia {fmt_number(jm * scale, 3)} kg m^2 (x{fmt_number(scale, 3)} of the model's "
                f"{fmt_number(jm, 3)} kg m^2: {'+' if change >= 0 else '-'}{fmt_number(abs(change), 3)} kg of "
                f"rotating mass per side at the wheels)")

    def repredict(self, b: PhysicsBasis, log: InteractionLog, value: float, index: Any = None) -> np.ndarray:
        motor = dataclasses.replace(b.robot.motor, rotor_inertia_kg_m2=b.robot.motor.rotor_inertia_kg_m2 * value)
        return motoring_currents_a(b, log, robot=b.robot.replace(motor=motor))
