"""Physics energy model of a two-sided (differential or skid-steer) DC-motor drive.

:class:`PhysicsEnergyModel` follows the physics paper (Turkish J. EECS 2022, "A novel
energy consumption model for autonomous mobile robot") and adds skid-steer turning
resistance, which that paper lacks. Every effect can be switched on or off by name
(:data:`EFFECTS`); everything is vectorised over arrays of samples.

Model, per sample and per side (left = column 0, right = column 1)
-------------------------------------------------------------------
Kinematics (ICR form): side speeds ``v_side = v -/+ omega * chi * B / 2`` and side
accelerations likewise from ``alpha`` (yaw acceleration). Normal load
``N = m g cos(beta)``, shared equally, ``N_side = N / 2``.

Longitudinal force demand at the wheels of one side, ``F_side`` (N), sum of:

- ``"inertia"``: ``m/2 * a`` plus the yaw term ``+/- I_z * alpha / B``; the rotor
  inertia ``Jm * d(omega_m)/dt`` is added at the motor shaft. (The paper's
  ``m/2 r^2 d(omega)/dt`` written as a force.)
- ``"slope"``: ``m/2 * g * sin(beta)`` with ``beta`` the pitch of the forward axis
  (positive nose-up). (The paper's ``m/2 g r sin(beta)`` as a force.)
- friction of the rolling contact, opposing the side's motion (or, at standstill, the
  intended motion, ``sign(a_side)``):

  * ``"coulomb_friction"``: ``Crr * N_side`` — for a *rolling* wheel the speed-independent
    (Coulomb) resistance is the rolling resistance;
  * ``"static_friction"``: at standstill (``|v_side| <= 1e-6 m/s``) the breakaway excess
    ``Crr * (mu_s / mu_k - 1) * N_side``;
  * ``"stribeck"``: while moving, the same excess decaying as ``exp(-c_s |v_side|)``;
  * ``"viscous_friction"``: ``c_v * N_side * v_side`` at the contact plus the motor's
    ``bm * omega_m`` at the shaft (the paper's ``b_z omega``).

  Deviation from the paper, on purpose: the paper's friction law uses the *sliding*
  coefficients (stone mu_s 1.0, mu_k 0.7) against the robot's weight. That is the force to
  drag the robot on locked wheels, which a rolling robot never pays (for a Husky on asphalt
  it would give ~170 W at 0.5 m/s against the ~4 W rolling anchor). Here the sliding
  coefficients keep their physical roles — the traction limit of slip, the lateral friction
  of skid steering and the static-to-kinetic ratio of the breakaway — and the longitudinal
  friction level is the rolling resistance ``Crr``.
- ``"turning_resistance"`` (skid-steer only): the turning-resistance moment
  ``M_r = mu_lat(R) * N * a`` (Wong, point-contact 4-wheel form, ``a`` = half wheelbase,
  ``mu_lat(R) = mu_lat / (0.925 + 0.15 R / B)``, ``R = |v / omega|``) shared as
  ``-/+ M_r / B`` between left and right, as in Dogru & Marques 2018 / Morales 2009
  (friction power grows with ``|omega|`` and falls with the turn radius). With the ICR
  kinematics its power is ``chi * M_r * |omega|``.
- ``"lateral_slip"``: the centripetal force ``F_y = m v omega`` needs a slip angle
  ``tan(alpha_s) = k_y * |F_y| / (mu_k N)``; its drag ``|F_y| tan(alpha_s)`` opposes the
  motion, shared between the sides (zero on straight routes).

Wheel speed: ``omega_w = v_side / r``; with ``"longitudinal_slip"`` the slip
``i = -i0 ln(1 - |F_side| / (mu_k N_side))`` (capped at 0.95, where the traction limit is
flagged) makes the wheel spin faster when driving (``v_side / (r (1 - i))``) and slower
when braking (``v_side (1 - i) / r``); the slip loss ``F_side (r omega_w - v_side) >= 0``
appears in the motor power through ``omega_w``.

Motor (per side, one motor): ``omega_m = N_g * omega_w``; shaft torque
``T_m = F_side r / (N_g eta)`` when motoring (or ``F_side r eta / N_g`` when back-driven,
``eta = 1`` unless ``"gear_losses"``) plus the rotor inertia and ``bm`` terms.
Saturation: ``"speed_saturation"`` clips ``|omega_m|`` to ``max_speed_radps``;
``"torque_saturation"`` clips ``|T_m|`` to ``max_torque_nm`` and to the paper's
``P_max = T_max * omega_max`` (``|T_m omega_m| <= P_max``). Clipped samples are flagged in
:attr:`PowerBreakdown.saturated`, never clipped silently; a kinematic input that saturates
is a motion the robot cannot actually perform. The limits are the paper's rectangle, not
the DC motor's torque-speed line ``Kt (V_b - Ke |omega_m|) / Ra``: with kinematic inputs
that line would give zero power at the no-load speed (where the paper's robot cruises).
Samples beyond the line are flagged in :attr:`PowerBreakdown.voltage_exceeded`.

Current ``I = T_m / Kt``; electrical power ``P_e = Ke omega_m I + Ra I^2``. The armature
heat ``Ra I^2`` (``"armature_heat"``) is the only copper-loss term: with the switch off
the motor is an ideal converter, so the heat is never counted twice. The inductance energy
``La I^2 / 2`` is returned when the current falls and is neglected (``La dI/dt`` averages
to zero over a drive). Battery side: each side's ``P_e`` counts in full when >= 0 and times
``regen_efficiency`` when negative (0 by default: no regeneration, a back-driven side is
pure loss).

Electronics: ``"sensor"`` adds ``sensor_power_w + sensor_power_per_mps_w * |v|``;
``"control"`` adds the control-board power: standby when stopped, start-up during the first
``startup_duration_s`` after each start from rest (needs ``time_s``), stable otherwise.
The paper writes parts of the control energy with ``t^2`` terms, which is dimensionally
inconsistent with a power in W; here the control energy is the time integral of the
piecewise-constant board power, ``E = sum_k P_k * t_k``.
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from terrain.errors import DataError, InvalidParameterError, UnknownNameError

from .params import GRAVITY_MPS2, GroundParams, RobotParams

__all__ = ["EFFECTS", "PhysicsEnergyModel", "PowerBreakdown"]

#: Names of every effect of :class:`PhysicsEnergyModel`.
EFFECTS: tuple[str, ...] = (
    "inertia",
    "slope",
    "static_friction",
    "coulomb_friction",
    "stribeck",
    "viscous_friction",
    "longitudinal_slip",
    "lateral_slip",
    "turning_resistance",
    "gear_losses",
    "torque_saturation",
    "speed_saturation",
    "armature_heat",
    "sensor",
    "control",
)

_STANDSTILL_MPS = 1e-6  # |v_side| at or below this is standstill (static friction)
_STOPPED_MPS = 1e-3  # robot counts as stopped for the control board below this speed
_STOPPED_RADPS = 1e-3  # ... and below this yaw rate
_MAX_SLIP = 0.95

_trapezoid = getattr(np, "trapezoid", None) or np.trapz


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class PowerBreakdown:
    """Power of each sample, split by where it goes (returned by ``PhysicsEnergyModel.power``).

    Arrays of shape ``(n,)`` unless noted; ``(n, 2)`` arrays hold ``[left, right]``.
    Wheel-level components (``*_power_w`` other than the battery-side totals) are the
    demanded mechanical power ``sum_sides F_component * v_side`` (may be negative, e.g.
    slope downhill), before gearbox, motor and saturation.

    Attributes
    ----------
    total_power_w : battery-side total (drive + sensor + control), W.
    drive_power_w : battery-side motor power summed over both sides, W.
    sensor_power_w, control_power_w : electronics, W.
    armature_heat_power_w : ``Ra I^2`` summed over sides (0 with the effect off), W.
    motor_current_a : (n, 2) signed motor current per side, A.
    motor_voltage_v : (n, 2) motor terminal voltage ``Ke omega_m + Ra I``, V.
    motor_speed_radps : (n, 2) motor shaft speed (after speed saturation), rad/s.
    motor_torque_nm : (n, 2) motor shaft torque (after torque saturation), N m.
    motor_electrical_power_w : (n, 2) signed electrical power per side, W.
    inertia_power_w, slope_power_w, friction_power_w, viscous_power_w, turning_power_w,
    lateral_slip_power_w, longitudinal_slip_power_w : wheel-level components, W
        (friction = Coulomb + static + Stribeck; viscous = contact part only).
    saturated : bool, any side clipped by torque or speed saturation.
    traction_exceeded : bool, a side demands more than ``mu_k N_side`` (or the lateral
        force exceeds ``mu_k N``): the ground cannot carry the commanded motion.
    voltage_exceeded : bool, a side's terminal voltage ``|Ke omega_m + Ra I|`` exceeds the
        battery voltage: the DC motor's torque-speed line cannot deliver this sample
        (informative; saturation uses the paper's rectangular limits).
    """

    total_power_w: np.ndarray
    drive_power_w: np.ndarray
    sensor_power_w: np.ndarray
    control_power_w: np.ndarray
    armature_heat_power_w: np.ndarray
    motor_current_a: np.ndarray
    motor_voltage_v: np.ndarray
    motor_speed_radps: np.ndarray
    motor_torque_nm: np.ndarray
    motor_electrical_power_w: np.ndarray
    inertia_power_w: np.ndarray
    slope_power_w: np.ndarray
    friction_power_w: np.ndarray
    viscous_power_w: np.ndarray
    turning_power_w: np.ndarray
    lateral_slip_power_w: np.ndarray
    longitudinal_slip_power_w: np.ndarray
    saturated: np.ndarray
    traction_exceeded: np.ndarray
    voltage_exceeded: np.ndarray

    def __post_init__(self) -> None:
        n = np.shape(self.total_power_w)
        if len(n) != 1:
            raise InvalidParameterError(
                f"PowerBreakdown.total_power_w must be 1-D, got shape {n!r}"
            )
        for name, value in vars(self).items():
            arr = np.asarray(value)
            expected = (n[0], 2) if name.startswith("motor_") else n
            if arr.shape != expected:
                raise InvalidParameterError(
                    f"PowerBreakdown.{name} must have shape {expected!r}, got {arr.shape!r}"
                )
            object.__setattr__(self, name, _readonly(arr))

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.total_power_w.shape[0])

    def energy_j(self, time_s: Any, component: str = "total_power_w") -> float:
        """Integrate a power component over ``time_s`` with the trapezoid rule.

        Parameters
        ----------
        time_s : array_like, shape (n,)
            Strictly increasing sample times, s.
        component : str
            Name of a ``(n,)`` power field (default ``"total_power_w"``).

        Returns
        -------
        float
            Energy in J.

        Raises
        ------
        DataError
            Times not finite, not strictly increasing or of the wrong length.
        UnknownNameError
            ``component`` is not a ``(n,)`` power field.
        """
        names = [k for k in vars(self) if k.endswith("_power_w") and not k.startswith("motor_")]
        if component not in names:
            raise UnknownNameError(
                f"component {component!r} is unknown; expected one of {sorted(names)!r}"
            )
        t = _check_time(time_s, self.n_samples)
        return float(_trapezoid(getattr(self, component), t))


def _check_time(time_s: Any, n: int) -> np.ndarray:
    t = np.asarray(time_s, dtype=np.float64)
    if t.ndim != 1 or t.shape[0] != n:
        raise DataError(f"time_s must be 1-D with {n} samples, got shape {t.shape!r}")
    if not np.all(np.isfinite(t)):
        raise DataError(f"time_s must be finite, got {t[~np.isfinite(t)][:3]!r}")
    if n > 1 and np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0))
        raise DataError(
            f"time_s must be strictly increasing; time_s[{k}]={t[k]!r}, "
            f"time_s[{k + 1}]={t[k + 1]!r}"
        )
    return t


def _as_finite(name: str, value: Any) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidParameterError(f"{name} must be numeric, got {value!r}") from None
    if not np.all(np.isfinite(arr)):
        bad = arr[~np.isfinite(arr)] if arr.ndim else arr
        raise InvalidParameterError(
            f"{name} must be finite (no NaN or inf), got {np.atleast_1d(bad)[:3]!r}"
        )
    return arr


class _GroundArrays:
    """Per-sample ground coefficients, built from one GroundParams or a list plus indices."""

    __slots__ = ("mu_s", "mu_k", "c_s", "c_v", "crr", "mu_lat", "i0", "k_y")

    def __init__(self, ground: Any, ground_index: Any, n: int) -> None:
        if isinstance(ground, GroundParams):
            grounds: Sequence[GroundParams] = [ground]
            idx = np.zeros(n, dtype=np.intp)
            if ground_index is not None:
                raise InvalidParameterError(
                    "ground_index must be None when ground is a single GroundParams, "
                    f"got {ground_index!r}"
                )
        else:
            if not isinstance(ground, Sequence) or isinstance(ground, str) or not ground:
                raise InvalidParameterError(
                    "ground must be a GroundParams or a non-empty sequence of GroundParams, "
                    f"got {ground!r}"
                )
            for k, g in enumerate(ground):
                if not isinstance(g, GroundParams):
                    raise InvalidParameterError(
                        f"ground[{k}] must be a GroundParams, got {type(g).__name__!r}"
                    )
            grounds = ground
            if ground_index is None:
                raise InvalidParameterError(
                    "ground_index is required when ground is a sequence of GroundParams"
                )
            raw = np.asarray(ground_index)
            if raw.dtype.kind not in "iu":
                raise InvalidParameterError(
                    f"ground_index must hold integers, got dtype {raw.dtype!s}"
                )
            idx = np.broadcast_to(raw, (n,)) if raw.ndim <= 1 and raw.size in (1, n) else None
            if idx is None:
                raise InvalidParameterError(
                    f"ground_index must have {n} entries, got shape {raw.shape!r}"
                )
            if np.any((idx < 0) | (idx >= len(grounds))):
                bad = idx[(idx < 0) | (idx >= len(grounds))][:3]
                raise InvalidParameterError(
                    f"ground_index must lie in [0, {len(grounds) - 1}], got {bad!r}"
                )
        table = np.array(
            [
                [g.static_friction_coef, g.coulomb_friction_coef,
                 g.stribeck_velocity_coef_s_per_m, g.viscous_friction_coef_s_per_m,
                 g.rolling_resistance_coef, g.effective_lateral_friction_coef,
                 g.longitudinal_slip_coef, g.lateral_slip_coef]
                for g in grounds
            ],
            dtype=np.float64,
        )
        cols = table[idx]
        (self.mu_s, self.mu_k, self.c_s, self.c_v, self.crr, self.mu_lat, self.i0,
         self.k_y) = (cols[:, k] for k in range(8))


class PhysicsEnergyModel:
    """Battery power and energy of a two-sided DC-motor drive, each effect switchable.

    See the module docstring for the equations and the documented deviations from the
    physics paper.

    Parameters
    ----------
    robot : RobotParams
        The vehicle.
    effects : iterable of str, optional
        Effects to include (names from :data:`EFFECTS`); ``None`` (default) includes all.
        Validated here, not in a ``fit`` (the model has nothing to learn yet); stored as a
        tuple in :data:`EFFECTS` order.

    Raises
    ------
    InvalidParameterError
        ``robot`` is not a RobotParams, or ``effects`` is a bare string.
    UnknownNameError
        An effect name is not in :data:`EFFECTS`.

    Examples
    --------
    >>> from energy import PhysicsEnergyModel, ground_preset, robot_preset
    >>> model = PhysicsEnergyModel(robot_preset("husky"))
    >>> e = model.energy_per_metre_j(0.5, [0.0, 0.1], ground_preset("asphalt"))
    >>> bool(e[1] > e[0] > 0)
    True
    """

    def __init__(self, robot: RobotParams, effects: Iterable[str] | None = None) -> None:
        if not isinstance(robot, RobotParams):
            raise InvalidParameterError(
                f"robot must be a RobotParams, got {type(robot).__name__!r}"
            )
        if effects is None:
            chosen = set(EFFECTS)
        else:
            if isinstance(effects, str):
                raise InvalidParameterError(
                    f"effects must be an iterable of effect names, not a string: {effects!r}"
                )
            chosen = set()
            for name in effects:
                if name not in EFFECTS:
                    raise UnknownNameError(
                        f"effect {name!r} is unknown; expected names from {EFFECTS!r}"
                    )
                chosen.add(name)
        self.robot = robot
        self.effects: tuple[str, ...] = tuple(e for e in EFFECTS if e in chosen)

    def __repr__(self) -> str:
        return f"PhysicsEnergyModel(robot={self.robot.name!r}, effects={self.effects!r})"

    def has(self, effect: str) -> bool:
        """Whether ``effect`` is switched on (raises UnknownNameError for unknown names)."""
        if effect not in EFFECTS:
            raise UnknownNameError(f"effect {effect!r} is unknown; expected names from {EFFECTS!r}")
        return effect in self.effects

    # ------------------------------------------------------------------ core
    def power(
        self,
        speed_mps: Any,
        omega_radps: Any,
        ground: GroundParams | Sequence[GroundParams],
        *,
        accel_mps2: Any = 0.0,
        alpha_radps2: Any = 0.0,
        slope_rad: Any = 0.0,
        time_s: Any = None,
        ground_index: Any = None,
    ) -> PowerBreakdown:
        """Power of each sample, with per-side motor current and per-effect components.

        Parameters
        ----------
        speed_mps : array_like
            Forward speed ``v`` (signed), m/s.
        omega_radps : array_like
            Yaw rate (positive counter-clockwise), rad/s.
        ground : GroundParams or sequence of GroundParams
            The ground of every sample, or a list indexed by ``ground_index``.
        accel_mps2 : array_like
            Forward acceleration ``dv/dt``, m/s^2 (default 0: steady).
        alpha_radps2 : array_like
            Yaw acceleration, rad/s^2 (default 0).
        slope_rad : array_like
            Pitch of the forward axis, positive nose-up (uphill when driving forward),
            in (-pi/2, pi/2).
        time_s : array_like, optional
            Strictly increasing sample times; only used for the control board's start-up
            interval (without it a moving robot's board is at its stable power).
        ground_index : array_like of int, optional
            Index into ``ground`` per sample (required when ``ground`` is a sequence).

        All per-sample arguments broadcast to one 1-D shape ``(n,)``.

        Returns
        -------
        PowerBreakdown

        Raises
        ------
        InvalidParameterError
            NaN/inf inputs, slopes outside (-pi/2, pi/2), shapes that do not broadcast to
            1-D, bad ground or ground_index.
        DataError
            ``time_s`` not strictly increasing.
        """
        v, omega, acc, alpha, slope = self._broadcast(
            speed_mps=speed_mps, omega_radps=omega_radps, accel_mps2=accel_mps2,
            alpha_radps2=alpha_radps2, slope_rad=slope_rad,
        )
        n = v.shape[0]
        gr = _GroundArrays(ground, ground_index, n)
        t = None if time_s is None else _check_time(time_s, n)
        return self._compute(v, omega, acc, alpha, slope, gr, t)

    def energy_j(
        self,
        time_s: Any,
        speed_mps: Any,
        omega_radps: Any,
        ground: GroundParams | Sequence[GroundParams],
        *,
        accel_mps2: Any = None,
        alpha_radps2: Any = None,
        slope_rad: Any = 0.0,
        ground_index: Any = None,
    ) -> float:
        """Battery energy (J) of a sampled motion, integrated with the trapezoid rule.

        Parameters
        ----------
        time_s : array_like, shape (n,)
            Strictly increasing sample times, s.
        speed_mps, omega_radps, slope_rad, ground, ground_index
            As in :meth:`power`.
        accel_mps2, alpha_radps2 : array_like, optional
            Accelerations; ``None`` (default) differentiates ``speed_mps`` /
            ``omega_radps`` over ``time_s`` (``numpy.gradient``).

        Returns
        -------
        float

        Raises
        ------
        InvalidParameterError, DataError
            As in :meth:`power`; also fewer than 2 samples.
        """
        t = np.asarray(time_s, dtype=np.float64)
        if t.ndim != 1 or t.shape[0] < 2:
            raise DataError(f"time_s must be 1-D with at least 2 samples, got shape {t.shape!r}")
        t = _check_time(t, t.shape[0])
        n = t.shape[0]
        v, w = _as_finite("speed_mps", speed_mps), _as_finite("omega_radps", omega_radps)
        if v.size not in (1, n) or w.size not in (1, n) or v.ndim > 1 or w.ndim > 1:
            raise InvalidParameterError(
                f"speed_mps and omega_radps must be scalars or have {n} samples like time_s, "
                f"got shapes {v.shape!r} and {w.shape!r}"
            )
        v = np.broadcast_to(v, (n,)).astype(np.float64)
        w = np.broadcast_to(w, (n,)).astype(np.float64)
        acc = np.gradient(v, t) if accel_mps2 is None else accel_mps2
        alpha = np.gradient(w, t) if alpha_radps2 is None else alpha_radps2
        res = self.power(v, w, ground, accel_mps2=acc, alpha_radps2=alpha,
                         slope_rad=slope_rad, time_s=t, ground_index=ground_index)
        return float(_trapezoid(res.total_power_w, t))

    # --------------------------------------------------------------- planner
    def energy_per_metre_j(self, speed_mps: float, grade: Any, ground: GroundParams,
                           *, infeasible: str = "inf") -> np.ndarray:
        """Energy per metre (J/m) of steady straight driving on constant grades.

        Includes the electronics (sensor and stable control power divided by the speed)
        when those effects are on. Battery-side, so >= 0 for every grade when
        ``regen_efficiency`` is 0.

        A grade is *infeasible* at ``speed_mps`` when the drive cannot hold that speed on
        it: a side saturates (torque, power or speed limit, with the saturation effects on)
        or demands more than the traction limit (with a slip effect on) — uphill beyond the
        climbing limit, or downhill beyond what the motors can hold back (see
        :meth:`max_feasible_grade`). Planners need such grades to be impassable, not
        cheap, so by default they cost ``+inf`` (:class:`planner.EnergyCost` then refuses
        them in that direction only).

        Parameters
        ----------
        speed_mps : float
            Driving speed, m/s: > 0 and at most ``robot.max_speed_mps``.
        grade : array_like
            ``tan(beta) = dz/dl`` along the direction of motion, positive uphill.
        ground : GroundParams
        infeasible : {"inf", "capped"}
            ``"inf"`` (default) for infeasible grades; ``"capped"`` returns the saturated
            (capped) power instead — what the model says is drawn while the robot, driven
            there anyway, falls short of the commanded speed.

        Returns
        -------
        numpy.ndarray
            Same shape as ``grade``.

        Raises
        ------
        InvalidParameterError
            Non-positive or non-finite speed, a speed above ``robot.max_speed_mps``, NaN
            grades, ``ground`` not a GroundParams, an unknown ``infeasible``.

        Examples
        --------
        >>> from energy import PhysicsEnergyModel, ground_preset, robot_preset
        >>> m = PhysicsEnergyModel(robot_preset("jackal"), effects=["slope"])
        >>> float(m.energy_per_metre_j(1.0, 0.0, ground_preset("asphalt")))
        0.0
        """
        speed = self._positive_scalar("speed_mps", speed_mps)
        if speed > self.robot.max_speed_mps:
            raise InvalidParameterError(
                f"speed_mps {speed_mps!r} exceeds the robot's max_speed_mps "
                f"{self.robot.max_speed_mps!r} ({self.robot.name!r})"
            )
        if infeasible not in ("inf", "capped"):
            raise UnknownNameError(f"infeasible must be 'inf' or 'capped', got {infeasible!r}")
        g = _as_finite("grade", grade)
        self._single_ground(ground)
        flat = g.reshape(-1)
        if flat.size == 0:
            return np.zeros(g.shape)
        res = self.power(speed, 0.0, ground, slope_rad=np.arctan(flat))
        e = res.total_power_w / speed
        if infeasible == "inf":
            e = np.where(res.saturated | res.traction_exceeded, np.inf, e)
        return e.reshape(g.shape)

    def max_feasible_grade(self, speed_mps: float, ground: GroundParams,
                           resolution: float = 1e-3) -> float:
        """Steepest uphill grade (``tan(beta)``) drivable at a steady ``speed_mps``.

        A grade is feasible when no sample saturates (with the saturation effects on) and
        the traction limit is not exceeded (with a slip effect on); a planner's slope
        limit should not exceed it. Searched on a grid of step ``resolution`` up to 5.0.

        Returns
        -------
        float
            The largest feasible grade on the grid (0.0 if even flat ground is not).

        Raises
        ------
        InvalidParameterError
            Non-positive speed or resolution, ``ground`` not a GroundParams.
        """
        speed = self._positive_scalar("speed_mps", speed_mps)
        step = self._positive_scalar("resolution", resolution)
        self._single_ground(ground)
        grades = np.arange(0.0, 5.0 + step / 2, step)
        res = self.power(speed, 0.0, ground, slope_rad=np.arctan(grades))
        bad = res.saturated | res.traction_exceeded
        if not bad.any():
            return float(grades[-1])
        first = int(np.argmax(bad))
        return float(grades[first - 1]) if first > 0 else 0.0

    def segment_energy_j(self, length_m: Any, speed_mps: float, grade: Any,
                         ground: GroundParams) -> np.ndarray:
        """Energy (J) of straight segments: ``length_m * energy_per_metre_j``.

        ``length_m`` (>= 0) and ``grade`` broadcast together.

        Raises
        ------
        InvalidParameterError
            Negative or NaN lengths, plus the errors of :meth:`energy_per_metre_j`.
        """
        length = _as_finite("length_m", length_m)
        if np.any(length < 0):
            raise InvalidParameterError(
                f"length_m must be >= 0, got {np.atleast_1d(length[length < 0])[:3]!r}"
            )
        length, g = np.broadcast_arrays(length, _as_finite("grade", grade))
        return length * self.energy_per_metre_j(speed_mps, g, ground)

    def turn_energy_j(self, heading_change_rad: Any, ground: GroundParams,
                      grade: Any = 0.0) -> np.ndarray:
        """Energy (J) of turning in place by ``|heading_change_rad|``.

        The robot pivots at ``robot.turn_rate_radps`` (steady, no acceleration terms) for
        ``|heading_change_rad| / turn_rate_radps`` seconds; the energy includes the
        electronics over that time when those effects are on. ``grade`` is taken as the
        robot's pitch during the turn.

        Parameters
        ----------
        heading_change_rad : array_like
            Heading changes (sign ignored), rad.
        ground : GroundParams
        grade : array_like
            ``tan(pitch)``; broadcasts with ``heading_change_rad``.

        Returns
        -------
        numpy.ndarray
            ``>= 0``, zero for a zero heading change; broadcast shape.

        Raises
        ------
        InvalidParameterError
            NaN inputs, ``ground`` not a GroundParams.
        """
        dh = np.abs(_as_finite("heading_change_rad", heading_change_rad))
        g = _as_finite("grade", grade)
        self._single_ground(ground)
        dh, g = np.broadcast_arrays(dh, g)
        if dh.size == 0:
            return np.zeros(dh.shape)
        rate = self.robot.turn_rate_radps
        res = self.power(0.0, rate, ground, slope_rad=np.arctan(g.reshape(-1)))
        return (res.total_power_w.reshape(dh.shape) * dh / rate)

    # -------------------------------------------------------------- helpers
    @staticmethod
    def _positive_scalar(name: str, value: Any) -> float:
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise InvalidParameterError(f"{name} must be a finite scalar > 0, got {value!r}")
        if not np.isfinite(value) or value <= 0:
            raise InvalidParameterError(f"{name} must be a finite scalar > 0, got {value!r}")
        return float(value)

    @staticmethod
    def _single_ground(ground: Any) -> None:
        if not isinstance(ground, GroundParams):
            raise InvalidParameterError(
                f"ground must be a GroundParams, got {type(ground).__name__!r}"
            )

    @staticmethod
    def _broadcast(**arrays: Any) -> list[np.ndarray]:
        checked = {k: _as_finite(k, a) for k, a in arrays.items()}
        try:
            out = np.broadcast_arrays(*checked.values())
        except ValueError:
            shapes = {k: a.shape for k, a in checked.items()}
            raise InvalidParameterError(
                f"per-sample inputs must broadcast to one 1-D shape, got shapes {shapes!r}"
            ) from None
        if out[0].ndim > 1:
            raise InvalidParameterError(
                f"per-sample inputs must be scalars or 1-D arrays, got shape {out[0].shape!r}"
            )
        out = [np.atleast_1d(np.array(a, dtype=np.float64)) for a in out]
        slope = out[-1]
        if np.any(np.abs(slope) >= np.pi / 2):
            bad = slope[np.abs(slope) >= np.pi / 2][:3]
            raise InvalidParameterError(f"slope_rad must lie in (-pi/2, pi/2), got {bad!r}")
        return out

    def _compute(self, v: np.ndarray, omega: np.ndarray, acc: np.ndarray, alpha: np.ndarray,
                 slope: np.ndarray, gr: _GroundArrays, t: np.ndarray | None) -> PowerBreakdown:
        rb, mo, on = self.robot, self.robot.motor, set(self.effects)
        n = v.shape[0]
        m, g, r, b = rb.mass_kg, GRAVITY_MPS2, rb.wheel_radius_m, rb.track_width_m
        half = rb.track_width_multiplier * b / 2.0
        side = np.array([-1.0, 1.0])  # left, right

        normal = m * g * np.cos(slope)  # (n,)
        n_side = (normal / 2.0)[:, None]  # (n,1)
        v_side = v[:, None] + omega[:, None] * half * side  # (n,2)
        a_side = acc[:, None] + alpha[:, None] * half * side
        moving = np.abs(v_side) > _STANDSTILL_MPS
        direction = np.where(moving, np.sign(v_side), np.sign(a_side))
        zeros2 = np.zeros((n, 2))

        # -- wheel-level force components per side
        f_inertia = zeros2
        if "inertia" in on:
            yaw = rb.effective_yaw_inertia_kg_m2 * alpha / b
            f_inertia = (m / 2.0 * acc)[:, None] + yaw[:, None] * side
        f_slope = zeros2
        if "slope" in on:
            f_slope = np.broadcast_to((m / 2.0 * g * np.sin(slope))[:, None], (n, 2))
        friction_coef = np.zeros((n, 2))
        if "coulomb_friction" in on:
            friction_coef = friction_coef + gr.crr[:, None]
        excess = (gr.crr * (gr.mu_s / gr.mu_k - 1.0))[:, None]
        if "static_friction" in on:
            friction_coef = friction_coef + np.where(moving, 0.0, excess)
        if "stribeck" in on:
            decay = np.exp(-gr.c_s[:, None] * np.abs(v_side))
            friction_coef = friction_coef + np.where(moving, excess * decay, 0.0)
        f_friction = friction_coef * n_side * direction
        f_viscous = zeros2
        if "viscous_friction" in on:
            f_viscous = gr.c_v[:, None] * n_side * v_side
        f_turn = zeros2
        if "turning_resistance" in on and rb.drive_kind == "skid_steer":
            denom = 0.925 * np.abs(omega) * b + 0.15 * np.abs(v)
            safe = np.where(denom > 0, denom, 1.0)
            moment = np.where(
                denom > 0, gr.mu_lat * normal * (rb.wheelbase_m / 2.0) * omega * b / safe, 0.0
            )
            f_turn = (moment / b)[:, None] * side
        traction_exceeded = np.zeros(n, dtype=bool)
        f_lat = zeros2
        if "lateral_slip" in on:
            f_y = np.abs(m * v * omega)
            ratio_y = f_y / (gr.mu_k * normal)
            traction_exceeded |= ratio_y > 1.0
            drag = f_y * gr.k_y * ratio_y
            f_lat = (0.5 * drag * np.sign(v))[:, None] * np.ones(2)
        force = f_inertia + f_slope + f_friction + f_viscous + f_turn + f_lat

        # -- wheel speed with longitudinal slip
        omega_w = v_side / r
        if "longitudinal_slip" in on:
            # The skid-steer turning force is excluded: the sideways sliding it pays for is
            # already modelled by chi and the turning-resistance moment.
            ratio = np.abs(force - f_turn) / (gr.mu_k[:, None] * n_side)
            traction_exceeded |= np.any(ratio >= 1.0, axis=1)
            i0 = gr.i0[:, None]
            with np.errstate(divide="ignore"):
                slip = np.where(ratio < 1.0, -i0 * np.log1p(-np.minimum(ratio, 1.0 - 1e-12)),
                                _MAX_SLIP)
            slip = np.minimum(slip, _MAX_SLIP)
            driving = force * v_side >= 0
            omega_w = np.where(driving, v_side / (r * (1.0 - slip)), v_side * (1.0 - slip) / r)
        slip_power = force * (omega_w * r - v_side)

        # -- motor side
        ng = mo.gear_ratio
        eta = mo.gear_efficiency if "gear_losses" in on else 1.0
        torque_w = force * r
        omega_m = ng * omega_w
        motoring = torque_w * omega_w >= 0
        torque_m = np.where(motoring, torque_w / (ng * eta), torque_w * eta / ng)
        if "inertia" in on:
            torque_m = torque_m + mo.rotor_inertia_kg_m2 * ng * a_side / r
        if "viscous_friction" in on:
            torque_m = torque_m + mo.viscous_damping_nm_s_per_rad * omega_m
        saturated = np.zeros((n, 2), dtype=bool)
        if "speed_saturation" in on:
            over = np.abs(omega_m) > mo.max_speed_radps
            saturated |= over
            omega_m = np.clip(omega_m, -mo.max_speed_radps, mo.max_speed_radps)
        if "torque_saturation" in on:
            abs_w = np.abs(omega_m)
            limit = np.full((n, 2), mo.max_torque_nm)
            p_max = mo.max_torque_nm * mo.max_speed_radps
            safe_w = np.where(abs_w > 0, abs_w, 1.0)
            limit = np.where(abs_w > 0, np.minimum(limit, p_max / safe_w), limit)
            over = np.abs(torque_m) > limit * (1.0 + 1e-12)
            saturated |= over
            torque_m = np.clip(torque_m, -limit, limit)

        kt, ke, ra = (mo.torque_constant_nm_per_a, mo.back_emf_v_s_per_rad,
                      mo.armature_resistance_ohm)
        current = torque_m / kt
        heat = ra * current**2 if "armature_heat" in on else np.zeros((n, 2))
        p_elec = ke * omega_m * current + heat
        voltage = ke * omega_m + ra * current
        voltage_exceeded = np.any(np.abs(voltage) > rb.battery_voltage_v * (1.0 + 1e-9), axis=1)
        p_batt = np.where(p_elec >= 0, p_elec, rb.regen_efficiency * p_elec)
        drive = p_batt.sum(axis=1)

        sensor = np.zeros(n)
        if "sensor" in on:
            sensor = rb.sensor_power_w + rb.sensor_power_per_mps_w * np.abs(v)
        control = np.zeros(n)
        if "control" in on:
            control = self._control_power(v, omega, t)

        def wheel(f: np.ndarray) -> np.ndarray:
            return (f * v_side).sum(axis=1)

        return PowerBreakdown(
            total_power_w=drive + sensor + control,
            drive_power_w=drive,
            sensor_power_w=sensor,
            control_power_w=control,
            armature_heat_power_w=heat.sum(axis=1),
            motor_current_a=current,
            motor_voltage_v=voltage,
            motor_speed_radps=omega_m,
            motor_torque_nm=torque_m,
            motor_electrical_power_w=p_elec,
            inertia_power_w=wheel(f_inertia),
            slope_power_w=wheel(f_slope),
            friction_power_w=wheel(f_friction),
            viscous_power_w=wheel(f_viscous),
            turning_power_w=wheel(f_turn),
            lateral_slip_power_w=wheel(f_lat),
            longitudinal_slip_power_w=slip_power.sum(axis=1),
            saturated=saturated.any(axis=1),
            traction_exceeded=traction_exceeded,
            voltage_exceeded=voltage_exceeded,
        )

    def _control_power(self, v: np.ndarray, omega: np.ndarray, t: np.ndarray | None) -> np.ndarray:
        rb = self.robot
        moving = (np.abs(v) > _STOPPED_MPS) | (np.abs(omega) > _STOPPED_RADPS)
        power = np.where(moving, rb.control_stable_power_w, rb.control_standby_power_w)
        if t is not None and rb.startup_duration_s > 0:
            prev = np.concatenate(([False], moving[:-1]))
            start = moving & ~prev
            last = np.maximum.accumulate(np.where(start, np.arange(v.shape[0]), 0))
            startup = moving & (t - t[last] < rb.startup_duration_s)
            power = np.where(startup, rb.control_startup_power_w, power)
        return power.astype(np.float64)
