"""The drive-train equations of the physics energy model: per-sample forces, motor, battery power.

:func:`drive_power` is what :class:`~energy.physics.PhysicsEnergyModel` computes (the model
checks the inputs and calls it); it follows the physics paper (Turkish J. EECS 2022, "A novel
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

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from terrawatt_base.errors import InvalidParameterError

from .ground import GroundParams
from .power import PowerBreakdown
from .robot import GRAVITY_MPS2, RobotParams

__all__ = ["EFFECTS", "DRIVE_EFFECTS", "GroundArrays", "drive_power", "control_power", "battery_side_w"]

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
#: The effects of driving: :data:`EFFECTS` without the electronics (``sensor``, ``control``).
DRIVE_EFFECTS: tuple[str, ...] = tuple(e for e in EFFECTS if e not in ("sensor", "control"))

_STANDSTILL_MPS = 1e-6  # |v_side| at or below this is standstill (static friction)
_STOPPED_MPS = 1e-3  # robot counts as stopped for the control board below this speed
_STOPPED_RADPS = 1e-3  # ... and below this yaw rate
_MAX_SLIP = 0.95


class GroundArrays:
    """Per-sample ground coefficients, built from one GroundParams or a list plus indices.

    Attributes ``mu_s``, ``mu_k``, ``c_s``, ``c_v``, ``crr``, ``mu_lat``, ``i0``, ``k_y``
    (shape ``(n,)``): static and kinetic friction, Stribeck and viscous coefficients,
    rolling resistance, effective lateral friction, longitudinal and lateral slip
    coefficients of each sample's ground.

    Raises
    ------
    InvalidParameterError
        Not a GroundParams or a non-empty sequence of them; a missing, non-integer or
        out-of-range ``ground_index``.
    """

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


def drive_power(robot: RobotParams, effects: Iterable[str], v: np.ndarray, omega: np.ndarray, acc: np.ndarray,
                alpha: np.ndarray, slope: np.ndarray, gr: GroundArrays, t: np.ndarray | None) -> PowerBreakdown:
    """The :class:`PowerBreakdown` of checked per-sample inputs (see the module docstring).

    ``v``, ``omega``, ``acc``, ``alpha``, ``slope`` are finite float arrays of shape
    ``(n,)`` (slopes in (-pi/2, pi/2)), ``gr`` the grounds of the ``n`` samples and
    ``t`` their strictly increasing times or None; ``effects`` the names switched on.
    :class:`~energy.physics.PhysicsEnergyModel` checks user input before calling this.
    """
    rb, mo, on = robot, robot.motor, set(effects)
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
    p_batt = battery_side_w(p_elec, rb.regen_efficiency)
    drive = p_batt.sum(axis=1)

    sensor = np.zeros(n)
    if "sensor" in on:
        sensor = rb.sensor_power_w + rb.sensor_power_per_mps_w * np.abs(v)
    control = np.zeros(n)
    if "control" in on:
        control = control_power(rb, v, omega, t)

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


def battery_side_w(p_elec_w: np.ndarray, regen_efficiency: float) -> np.ndarray:
    """The battery side of a motor's electrical power: in full when >= 0, times ``regen_efficiency`` when negative."""
    return np.where(p_elec_w >= 0, p_elec_w, regen_efficiency * p_elec_w)


def control_power(robot: RobotParams, v: np.ndarray, omega: np.ndarray, t: np.ndarray | None) -> np.ndarray:
    """Control-board power (W): standby when stopped, start-up for ``startup_duration_s``
    after each start from rest (needs the times ``t``), stable otherwise."""
    rb = robot
    moving = (np.abs(v) > _STOPPED_MPS) | (np.abs(omega) > _STOPPED_RADPS)
    power = np.where(moving, rb.control_stable_power_w, rb.control_standby_power_w)
    if t is not None and rb.startup_duration_s > 0:
        prev = np.concatenate(([False], moving[:-1]))
        start = moving & ~prev
        last = np.maximum.accumulate(np.where(start, np.arange(v.shape[0]), 0))
        startup = moving & (t - t[last] < rb.startup_duration_s)
        power = np.where(startup, rb.control_startup_power_w, power)
    return power.astype(np.float64)
