"""Robot, motor and ground parameter sets (frozen, validated, SI units) and their presets.

Three frozen dataclasses describe what the physics model needs:

- :class:`MotorParams` — one DC drive motor with its gearbox (constants referred to the
  motor shaft; ``gear_ratio`` = motor turns per wheel turn).
- :class:`RobotParams` — the vehicle: mass, wheel and track geometry, drive kind, battery,
  electronics (sensor and control-board power) and one :class:`MotorParams` per side.
- :class:`GroundParams` — the wheel-ground contact: sliding friction (static, Coulomb,
  Stribeck), rolling and viscous resistance, lateral friction for skid-steer turning and
  slip coefficients. How each coefficient enters the model is documented in
  :mod:`energy.physics` (``PhysicsEnergyModel``).

Presets: :data:`ROBOT_PRESETS` (``"paper_seed"``, ``"jackal"``, ``"husky"``) and
:data:`GROUND_PRESETS`; look them up with :func:`robot_preset` / :func:`ground_preset`.
Values tagged *estimate* in the preset docstrings are plausible engineering values, not
manufacturer data; issue 3 fits the ground coefficients to logs.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import dataclass
from typing import Literal

from terrain.errors import InvalidParameterError, UnknownNameError

__all__ = [
    "MotorParams",
    "RobotParams",
    "GroundParams",
    "DRIVE_KINDS",
    "ROBOT_PRESETS",
    "GROUND_PRESETS",
    "robot_preset",
    "ground_preset",
]

#: Drive kinds understood by the physics model.
DRIVE_KINDS = ("differential", "skid_steer")

GRAVITY_MPS2 = 9.80665


def _check_finite(owner: str, name: str, value: object, *, low: float | None = None,
                  low_inclusive: bool = True, high: float | None = None,
                  high_inclusive: bool = True) -> None:
    """Raise InvalidParameterError unless ``value`` is a finite real number in range."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidParameterError(f"{owner}.{name} must be a real number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise InvalidParameterError(f"{owner}.{name} must be finite, got {value!r}")
    if low is not None and (v < low or (v == low and not low_inclusive)):
        op = ">=" if low_inclusive else ">"
        raise InvalidParameterError(f"{owner}.{name} must be {op} {low!r}, got {value!r}")
    if high is not None and (v > high or (v == high and not high_inclusive)):
        op = "<=" if high_inclusive else "<"
        raise InvalidParameterError(f"{owner}.{name} must be {op} {high!r}, got {value!r}")


def _check_name(owner: str, value: object) -> None:
    if not isinstance(value, str) or not value.strip():
        raise InvalidParameterError(f"{owner}.name must be a non-empty string, got {value!r}")


@dataclass(frozen=True, kw_only=True)
class MotorParams:
    """One DC drive motor and its gearbox; constants referred to the motor shaft.

    Parameters
    ----------
    torque_constant_nm_per_a : float
        Kt (> 0): motor torque per ampere.
    back_emf_v_s_per_rad : float
        Ke (> 0): back-EMF per motor rad/s (equal to Kt in SI for an ideal motor; papers
        often report slightly different values, both are kept).
    armature_resistance_ohm : float
        Ra (> 0): source of the armature heat ``Ra * I**2``.
    armature_inductance_h : float
        La (>= 0). Stored for completeness; the energy of ``La * dI/dt`` is
        ``La * I**2 / 2``, recovered when the current falls, so the model neglects it.
    rotor_inertia_kg_m2 : float
        Jm (>= 0) at the motor shaft (``Jm * d(omega_m)/dt`` in the torque balance).
    viscous_damping_nm_s_per_rad : float
        bm (>= 0) at the motor shaft (``bm * omega_m``).
    gear_ratio : float
        N (> 0): motor rad per wheel rad (1.0 when the constants are given at the output
        shaft, as for the physics paper's robot).
    gear_efficiency : float
        eta in (0, 1]: wheel torque = ``eta * N * motor torque`` when motoring,
        ``N * motor torque / eta`` when back-driven.
    max_torque_nm : float
        Peak motor torque (> 0) used by torque saturation.
    max_speed_radps : float
        Motor speed limit (> 0) used by speed saturation.
    """

    torque_constant_nm_per_a: float
    back_emf_v_s_per_rad: float
    armature_resistance_ohm: float
    armature_inductance_h: float = 0.0
    rotor_inertia_kg_m2: float = 0.0
    viscous_damping_nm_s_per_rad: float = 0.0
    gear_ratio: float = 1.0
    gear_efficiency: float = 1.0
    max_torque_nm: float
    max_speed_radps: float

    def __post_init__(self) -> None:
        own = "MotorParams"
        _check_finite(own, "torque_constant_nm_per_a", self.torque_constant_nm_per_a,
                      low=0.0, low_inclusive=False)
        _check_finite(own, "back_emf_v_s_per_rad", self.back_emf_v_s_per_rad,
                      low=0.0, low_inclusive=False)
        _check_finite(own, "armature_resistance_ohm", self.armature_resistance_ohm,
                      low=0.0, low_inclusive=False)
        _check_finite(own, "armature_inductance_h", self.armature_inductance_h, low=0.0)
        _check_finite(own, "rotor_inertia_kg_m2", self.rotor_inertia_kg_m2, low=0.0)
        _check_finite(own, "viscous_damping_nm_s_per_rad", self.viscous_damping_nm_s_per_rad,
                      low=0.0)
        _check_finite(own, "gear_ratio", self.gear_ratio, low=0.0, low_inclusive=False)
        _check_finite(own, "gear_efficiency", self.gear_efficiency, low=0.0,
                      low_inclusive=False, high=1.0)
        _check_finite(own, "max_torque_nm", self.max_torque_nm, low=0.0, low_inclusive=False)
        _check_finite(own, "max_speed_radps", self.max_speed_radps, low=0.0,
                      low_inclusive=False)


@dataclass(frozen=True, kw_only=True)
class RobotParams:
    """A wheeled or tracked ground robot with one drive motor per side.

    Parameters
    ----------
    name : str
        Label of the parameter set.
    mass_kg : float
        Total mass (> 0).
    wheel_radius_m : float
        Wheel (or sprocket) radius (> 0).
    track_width_m : float
        B: lateral distance between the left and right wheel contact lines (> 0).
    wheelbase_m : float
        Longitudinal distance between front and rear axles (>= 0); half of it is the lever
        ``a`` of the skid-steer turning-resistance moment ``M_r = mu_lat * m * g * a``.
    battery_voltage_v : float
        Supply voltage of the motor drivers (> 0); bounds the motor voltage under
        torque saturation.
    drive_kind : {"differential", "skid_steer"}
        ``"differential"``: two driven wheels plus casters, turning costs no lateral
        scrubbing. ``"skid_steer"``: wheels or tracks slide sideways while turning.
    motor : MotorParams
        The motor of each side (both sides are identical).
    driven_sides : int
        Number of independently driven sides sharing the load; the model is a left/right
        drive, so only 2 is accepted (kept explicit so the assumption is visible).
    sensor_power_w : float
        Sensor power at standstill (>= 0), always drawn.
    sensor_power_per_mps_w : float
        Extra sensor power per m/s of speed (>= 0), the speed-dependent part.
    control_standby_power_w, control_startup_power_w, control_stable_power_w : float
        Control-board power (>= 0) when stopped, during the first ``startup_duration_s``
        after each start from rest, and while moving afterwards.
    startup_duration_s : float
        Length of the start-up interval (>= 0).
    track_width_multiplier : float
        chi >= 1: the effective track of the ICR kinematics is ``chi * B`` (Clearpath's
        ``wheel_separation_multiplier``); use 1.0 for a differential drive.
    max_speed_mps, max_omega_radps : float
        Rated forward speed and yaw rate (> 0); informational limits for planners.
    turn_rate_radps : float
        Yaw rate of a turn in place used by ``PhysicsEnergyModel.turn_energy_j`` (> 0).
    regen_efficiency : float
        Fraction in [0, 1] of back-driven (generated) motor power returned to the battery;
        0.0 (default) means no regeneration: each side's battery power is clamped at >= 0.
    yaw_inertia_kg_m2 : float or None
        Body inertia about the vertical axis (>= 0). ``None`` (default) takes a uniform
        box of ``(wheelbase + 2 r) x track``: ``m (L**2 + B**2) / 12``.

    Raises
    ------
    InvalidParameterError
        Non-finite or out-of-range values, unknown drive kind, wrong field types.
    """

    name: str
    mass_kg: float
    wheel_radius_m: float
    track_width_m: float
    wheelbase_m: float
    battery_voltage_v: float
    drive_kind: Literal["differential", "skid_steer"]
    motor: MotorParams
    driven_sides: int = 2
    sensor_power_w: float = 0.0
    sensor_power_per_mps_w: float = 0.0
    control_standby_power_w: float = 0.0
    control_startup_power_w: float = 0.0
    control_stable_power_w: float = 0.0
    startup_duration_s: float = 0.0
    track_width_multiplier: float = 1.0
    max_speed_mps: float
    max_omega_radps: float
    turn_rate_radps: float
    regen_efficiency: float = 0.0
    yaw_inertia_kg_m2: float | None = None

    def __post_init__(self) -> None:
        own = "RobotParams"
        _check_name(own, self.name)
        _check_finite(own, "mass_kg", self.mass_kg, low=0.0, low_inclusive=False)
        _check_finite(own, "wheel_radius_m", self.wheel_radius_m, low=0.0, low_inclusive=False)
        _check_finite(own, "track_width_m", self.track_width_m, low=0.0, low_inclusive=False)
        _check_finite(own, "wheelbase_m", self.wheelbase_m, low=0.0)
        _check_finite(own, "battery_voltage_v", self.battery_voltage_v, low=0.0,
                      low_inclusive=False)
        if self.drive_kind not in DRIVE_KINDS:
            raise InvalidParameterError(
                f"RobotParams.drive_kind must be one of {DRIVE_KINDS!r}, got {self.drive_kind!r}"
            )
        if not isinstance(self.motor, MotorParams):
            raise InvalidParameterError(
                f"RobotParams.motor must be a MotorParams, got {type(self.motor).__name__!r}"
            )
        if isinstance(self.driven_sides, bool) or self.driven_sides != 2:
            raise InvalidParameterError(
                "RobotParams.driven_sides must be 2 (a left/right drive), "
                f"got {self.driven_sides!r}"
            )
        for name in ("sensor_power_w", "sensor_power_per_mps_w", "control_standby_power_w",
                     "control_startup_power_w", "control_stable_power_w", "startup_duration_s"):
            _check_finite(own, name, getattr(self, name), low=0.0)
        _check_finite(own, "track_width_multiplier", self.track_width_multiplier, low=1.0)
        for name in ("max_speed_mps", "max_omega_radps", "turn_rate_radps"):
            _check_finite(own, name, getattr(self, name), low=0.0, low_inclusive=False)
        _check_finite(own, "regen_efficiency", self.regen_efficiency, low=0.0, high=1.0)
        if self.yaw_inertia_kg_m2 is not None:
            _check_finite(own, "yaw_inertia_kg_m2", self.yaw_inertia_kg_m2, low=0.0)

    @property
    def effective_yaw_inertia_kg_m2(self) -> float:
        """``yaw_inertia_kg_m2``, or the uniform-box value when it is ``None``."""
        if self.yaw_inertia_kg_m2 is not None:
            return float(self.yaw_inertia_kg_m2)
        length_m = self.wheelbase_m + 2.0 * self.wheel_radius_m
        return self.mass_kg * (length_m**2 + self.track_width_m**2) / 12.0

    @property
    def weight_n(self) -> float:
        """``m * g`` in newtons."""
        return self.mass_kg * GRAVITY_MPS2

    def replace(self, **changes: object) -> RobotParams:
        """Return a copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True, kw_only=True)
class GroundParams:
    """Wheel-ground contact coefficients of one ground class.

    Parameters
    ----------
    name : str
        Ground class name (e.g. ``"asphalt"``).
    static_friction_coef : float
        mu_s: peak (static) sliding friction coefficient, >= ``coulomb_friction_coef``.
    coulomb_friction_coef : float
        mu_k (> 0): kinetic sliding friction coefficient; the traction limit of slip.
    stribeck_velocity_coef_s_per_m : float
        c_s (>= 0): decay rate of the static excess, ``exp(-c_s * |v|)``.
    viscous_friction_coef_s_per_m : float
        c_v (>= 0): viscous resistance per newton of normal load per m/s
        (force ``c_v * N * |v|``).
    rolling_resistance_coef : float
        Crr (>= 0): speed-independent rolling resistance per newton of normal load; the
        Coulomb level of the longitudinal resistance of a rolling wheel.
    lateral_friction_coef : float or None
        mu_lat (>= 0) of sideways sliding in skid-steer turns; ``None`` (default) takes
        ``coulomb_friction_coef``.
    longitudinal_slip_coef : float
        i0 (>= 0): slip-traction curve ``F / (mu_k N) = 1 - exp(-i / i0)``
        (Janosi-Hanamoto with ``i0 = K / L``, shear modulus over contact length).
    lateral_slip_coef : float
        k_y (>= 0): slip-angle tangent per unit of lateral force ratio,
        ``tan(alpha) = k_y * F_y / (mu_k N)``.

    Raises
    ------
    InvalidParameterError
        Non-finite or negative coefficients, ``static < coulomb``, empty name.
    """

    name: str
    static_friction_coef: float
    coulomb_friction_coef: float
    stribeck_velocity_coef_s_per_m: float = 0.0
    viscous_friction_coef_s_per_m: float = 0.0
    rolling_resistance_coef: float
    lateral_friction_coef: float | None = None
    longitudinal_slip_coef: float = 0.0
    lateral_slip_coef: float = 0.0

    def __post_init__(self) -> None:
        own = "GroundParams"
        _check_name(own, self.name)
        _check_finite(own, "coulomb_friction_coef", self.coulomb_friction_coef, low=0.0,
                      low_inclusive=False)
        _check_finite(own, "static_friction_coef", self.static_friction_coef, low=0.0)
        if self.static_friction_coef < self.coulomb_friction_coef:
            raise InvalidParameterError(
                f"GroundParams.static_friction_coef must be >= coulomb_friction_coef "
                f"({self.coulomb_friction_coef!r}), got {self.static_friction_coef!r}"
            )
        for name in ("stribeck_velocity_coef_s_per_m", "viscous_friction_coef_s_per_m",
                     "rolling_resistance_coef", "longitudinal_slip_coef", "lateral_slip_coef"):
            _check_finite(own, name, getattr(self, name), low=0.0)
        if self.lateral_friction_coef is not None:
            _check_finite(own, "lateral_friction_coef", self.lateral_friction_coef, low=0.0)

    @property
    def effective_lateral_friction_coef(self) -> float:
        """``lateral_friction_coef``, or ``coulomb_friction_coef`` when it is ``None``."""
        if self.lateral_friction_coef is not None:
            return float(self.lateral_friction_coef)
        return float(self.coulomb_friction_coef)

    def replace(self, **changes: object) -> GroundParams:
        """Return a copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)


# --------------------------------------------------------------------------- robot presets

def _paper_seed() -> RobotParams:
    # Physics paper (Turkish J. EECS 2022), seed robot. Motor constants are given at the
    # output shaft (gear ratio 1). Peak torque and speed are derived from the 12 V supply:
    # stall torque Kt V / Ra = 0.193 N m, no-load speed V / Ke = 13.51 rad/s (0.405 m/s).
    kt, ke, ra, volt = 0.8693, 0.8883, 53.94, 12.0
    motor = MotorParams(
        torque_constant_nm_per_a=kt,
        back_emf_v_s_per_rad=ke,
        armature_resistance_ohm=ra,
        armature_inductance_h=1e-6,
        rotor_inertia_kg_m2=0.038,
        viscous_damping_nm_s_per_rad=0.00075,
        gear_ratio=1.0,
        gear_efficiency=1.0,
        max_torque_nm=kt * volt / ra,
        max_speed_radps=volt / ke,
    )
    return RobotParams(
        name="paper_seed",
        mass_kg=0.8,
        wheel_radius_m=0.03,
        track_width_m=0.1,  # the paper's l = 0.1 m, taken as the wheel separation
        wheelbase_m=0.1,  # estimate (caster robot; only used for the default yaw inertia)
        battery_voltage_v=volt,
        drive_kind="differential",
        motor=motor,
        sensor_power_w=1.2,
        sensor_power_per_mps_w=0.0,  # the paper's speed coefficient is not in our summary
        control_standby_power_w=1.4,
        control_startup_power_w=2.4,
        control_stable_power_w=1.4,  # assumption: the board returns to 1.4 W after start-up
        startup_duration_s=2.0,  # assumption
        track_width_multiplier=1.0,
        max_speed_mps=0.4,
        max_omega_radps=8.0,
        turn_rate_radps=1.0,
    )


def _jackal() -> RobotParams:
    # Clearpath Jackal: geometry, mass, battery, chi from the manual / jackal_description /
    # jackal_control. Motor constants, gearing and electronics power are estimates.
    motor = MotorParams(
        torque_constant_nm_per_a=0.0545,  # estimate: no-load 25.6 V -> ~2.3 m/s wheel speed
        back_emf_v_s_per_rad=0.0545,
        armature_resistance_ohm=0.5,  # estimate
        armature_inductance_h=2e-4,  # estimate
        rotor_inertia_kg_m2=1.0e-5,  # estimate
        viscous_damping_nm_s_per_rad=5e-6,  # estimate
        gear_ratio=20.0,  # estimate
        gear_efficiency=0.85,  # estimate (gearbox + belt)
        max_torque_nm=0.0545 * 20.0,  # estimate: ~20 A peak
        max_speed_radps=25.6 / 0.0545,
    )
    return RobotParams(
        name="jackal",
        mass_kg=17.0,
        wheel_radius_m=0.098,
        track_width_m=0.37559,
        wheelbase_m=0.262,
        battery_voltage_v=25.6,
        drive_kind="skid_steer",
        motor=motor,
        sensor_power_w=5.0,  # estimate (IMU, GPS, camera)
        sensor_power_per_mps_w=1.0,  # estimate
        control_standby_power_w=15.0,  # estimate (MCU + onboard computer)
        control_startup_power_w=25.0,  # estimate
        control_stable_power_w=20.0,  # estimate
        startup_duration_s=1.0,  # estimate
        track_width_multiplier=1.5,
        max_speed_mps=2.0,
        max_omega_radps=4.0,
        turn_rate_radps=1.0,
    )


def _husky() -> RobotParams:
    # Clearpath Husky A200: geometry, mass, battery, chi from the manual / husky_description /
    # husky_control. Motor constants, gearing and electronics power are estimates.
    motor = MotorParams(
        torque_constant_nm_per_a=0.044,  # estimate: no-load 24 V -> ~1.14 m/s
        back_emf_v_s_per_rad=0.044,
        armature_resistance_ohm=0.3,  # estimate
        armature_inductance_h=3e-4,  # estimate
        rotor_inertia_kg_m2=1.6e-5,  # estimate
        viscous_damping_nm_s_per_rad=1e-5,  # estimate
        gear_ratio=78.71,  # estimate
        gear_efficiency=0.8,  # estimate (gearbox + chain)
        max_torque_nm=0.044 * 30.0,  # estimate: ~30 A peak per side
        max_speed_radps=24.0 / 0.044,
    )
    return RobotParams(
        name="husky",
        mass_kg=50.0,
        wheel_radius_m=0.1651,
        track_width_m=0.555,
        wheelbase_m=0.512,
        battery_voltage_v=24.0,
        drive_kind="skid_steer",
        motor=motor,
        sensor_power_w=15.0,  # estimate (lidar + IMU + GPS)
        sensor_power_per_mps_w=2.0,  # estimate
        control_standby_power_w=25.0,  # estimate (MCU, drivers, computer)
        control_startup_power_w=35.0,  # estimate
        control_stable_power_w=30.0,  # estimate
        startup_duration_s=1.0,  # estimate
        track_width_multiplier=1.875,
        max_speed_mps=1.0,
        max_omega_radps=2.0,
        turn_rate_radps=0.5,
    )


#: Robot presets by name. ``"paper_seed"``: the physics paper's 0.8 kg differential robot
#: (its constants, incl. the odd Ra = 53.94 ohm); ``"jackal"``: Clearpath Jackal (17 kg,
#: skid-steer, 4 wheels, 2 motors); ``"husky"``: Clearpath Husky A200 (50 kg, skid-steer).
ROBOT_PRESETS: dict[str, RobotParams] = {
    "paper_seed": _paper_seed(),
    "jackal": _jackal(),
    "husky": _husky(),
}


# -------------------------------------------------------------------------- ground presets

def _ground(name: str, mu_s: float, mu_k: float, crr: float, *, c_s: float = 20.0,
            c_v: float = 0.002, mu_lat: float | None = None, slip: float = 0.01,
            lat_slip: float = 0.02) -> GroundParams:
    return GroundParams(
        name=name,
        static_friction_coef=mu_s,
        coulomb_friction_coef=mu_k,
        stribeck_velocity_coef_s_per_m=c_s,
        viscous_friction_coef_s_per_m=c_v,
        rolling_resistance_coef=crr,
        lateral_friction_coef=mu_lat,
        longitudinal_slip_coef=slip,
        lateral_slip_coef=lat_slip,
    )


#: Ground presets by name. Sliding coefficients and rolling resistance from the ranges in
#: the project's physics notes (handbook values; small robot wheels at the high end);
#: ``stone`` (mu_s 1.0, mu_k 0.7, c_s 20 s/m) and ``sand`` (mu_k 0.5) from the physics paper.
#: Viscous and slip coefficients are estimates.
GROUND_PRESETS: dict[str, GroundParams] = {
    g.name: g
    for g in (
        _ground("asphalt", 0.8, 0.6, 0.015, mu_lat=0.55),
        _ground("concrete", 0.9, 0.7, 0.012, mu_lat=0.6),
        _ground("stone", 1.0, 0.7, 0.02, mu_lat=0.6),
        _ground("flooring", 0.7, 0.5, 0.010, mu_lat=0.45),
        _ground("coated_wood", 0.6, 0.45, 0.012, mu_lat=0.4),
        _ground("gravel", 0.7, 0.55, 0.05, c_v=0.01, mu_lat=0.5, slip=0.04, lat_slip=0.05),
        _ground("grass", 0.5, 0.4, 0.10, c_v=0.01, mu_lat=0.4, slip=0.05, lat_slip=0.06),
        _ground("sand", 0.6, 0.5, 0.15, c_v=0.03, mu_lat=0.4, slip=0.12, lat_slip=0.1),
        _ground("snow", 0.3, 0.25, 0.06, c_v=0.02, mu_lat=0.25, slip=0.1, lat_slip=0.1),
        _ground("ice", 0.1, 0.07, 0.01, c_v=0.0, mu_lat=0.07, slip=0.05, lat_slip=0.05),
    )
}


def robot_preset(name: str) -> RobotParams:
    """Return the robot preset called ``name``.

    Parameters
    ----------
    name : str
        One of ``ROBOT_PRESETS`` (``"paper_seed"``, ``"jackal"``, ``"husky"``).

    Returns
    -------
    RobotParams

    Raises
    ------
    UnknownNameError
        If ``name`` is not a preset; the message lists the valid names.

    Examples
    --------
    >>> from energy import robot_preset
    >>> robot_preset("husky").mass_kg
    50.0
    """
    try:
        return ROBOT_PRESETS[name]
    except (KeyError, TypeError):
        raise UnknownNameError(
            f"robot preset {name!r} is unknown; expected one of {sorted(ROBOT_PRESETS)!r}"
        ) from None


def ground_preset(name: str) -> GroundParams:
    """Return the ground preset called ``name``.

    Parameters
    ----------
    name : str
        One of ``GROUND_PRESETS`` (``"asphalt"``, ``"concrete"``, ``"stone"``, ``"grass"``,
        ``"gravel"``, ``"sand"``, ``"snow"``, ``"coated_wood"``, ``"flooring"``, ``"ice"``).

    Returns
    -------
    GroundParams

    Raises
    ------
    UnknownNameError
        If ``name`` is not a preset; the message lists the valid names.

    Examples
    --------
    >>> from energy import ground_preset
    >>> ground_preset("stone").static_friction_coef
    1.0
    """
    try:
        return GROUND_PRESETS[name]
    except (KeyError, TypeError):
        raise UnknownNameError(
            f"ground preset {name!r} is unknown; expected one of {sorted(GROUND_PRESETS)!r}"
        ) from None
