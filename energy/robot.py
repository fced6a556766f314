"""Robot and motor parameter sets (frozen, validated, SI units): the vehicle the physics model drives.

- :class:`MotorParams` — one DC drive motor with its gearbox (constants referred to the
  motor shaft; ``gear_ratio`` = motor turns per wheel turn).
- :class:`RobotParams` — the vehicle: mass, wheel and track geometry, drive kind, battery,
  electronics (sensor and control-board power) and one :class:`MotorParams` per side.

How each parameter enters the model is documented in :mod:`energy.drivetrain`; presets
are in :mod:`energy.params`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Literal

from terrawatt_base.checks import check_real, check_text
from terrawatt_base.errors import InvalidParameterError

__all__ = ["MotorParams", "RobotParams", "DRIVE_KINDS", "GRAVITY_MPS2"]

#: Drive kinds understood by the physics model.
DRIVE_KINDS = ("differential", "skid_steer")

#: Standard gravity (m/s^2).
GRAVITY_MPS2 = 9.80665


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
        check_real("torque_constant_nm_per_a", self.torque_constant_nm_per_a,
                   low=0.0, low_inclusive=False, owner=own)
        check_real("back_emf_v_s_per_rad", self.back_emf_v_s_per_rad,
                   low=0.0, low_inclusive=False, owner=own)
        check_real("armature_resistance_ohm", self.armature_resistance_ohm,
                   low=0.0, low_inclusive=False, owner=own)
        check_real("armature_inductance_h", self.armature_inductance_h, low=0.0, owner=own)
        check_real("rotor_inertia_kg_m2", self.rotor_inertia_kg_m2, low=0.0, owner=own)
        check_real("viscous_damping_nm_s_per_rad", self.viscous_damping_nm_s_per_rad,
                   low=0.0, owner=own)
        check_real("gear_ratio", self.gear_ratio, low=0.0, low_inclusive=False, owner=own)
        check_real("gear_efficiency", self.gear_efficiency, low=0.0,
                   low_inclusive=False, high=1.0, owner=own)
        check_real("max_torque_nm", self.max_torque_nm, low=0.0, low_inclusive=False, owner=own)
        check_real("max_speed_radps", self.max_speed_radps, low=0.0,
                   low_inclusive=False, owner=own)


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
    rest_current_a : float
        Current (>= 0, A) each side's current sensor logs while the robot stands still
        (:func:`energy.logs.at_rest`): the sensor's rest offset. It is a *measurement*: it is
        in every logged sample (before the driver's clamp at 0) but makes no torque and is
        never paid by the battery — :func:`energy.budget.log_battery_power_w` removes it from logged
        currents, :class:`~energy.physics.PhysicsEnergyModel` never includes it, and
        :class:`~energy.PhysicsCurrentModel` predicts it at rest. Default 0.

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
    rest_current_a: float = 0.0

    def __post_init__(self) -> None:
        own = "RobotParams"
        check_text("name", self.name, owner=own)
        check_real("mass_kg", self.mass_kg, low=0.0, low_inclusive=False, owner=own)
        check_real("wheel_radius_m", self.wheel_radius_m, low=0.0, low_inclusive=False, owner=own)
        check_real("track_width_m", self.track_width_m, low=0.0, low_inclusive=False, owner=own)
        check_real("wheelbase_m", self.wheelbase_m, low=0.0, owner=own)
        check_real("battery_voltage_v", self.battery_voltage_v, low=0.0,
                   low_inclusive=False, owner=own)
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
            check_real(name, getattr(self, name), low=0.0, owner=own)
        check_real("track_width_multiplier", self.track_width_multiplier, low=1.0, owner=own)
        for name in ("max_speed_mps", "max_omega_radps", "turn_rate_radps"):
            check_real(name, getattr(self, name), low=0.0, low_inclusive=False, owner=own)
        check_real("regen_efficiency", self.regen_efficiency, low=0.0, high=1.0, owner=own)
        if self.yaw_inertia_kg_m2 is not None:
            check_real("yaw_inertia_kg_m2", self.yaw_inertia_kg_m2, low=0.0, owner=own)
        check_real("rest_current_a", self.rest_current_a, low=0.0, owner=own)

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

    def to_plain(self) -> dict[str, object]:
        """The fields as plain values (the motor a nested mapping): what robot and model files store."""
        return dataclasses.asdict(self)

    @classmethod
    def from_plain(cls, value: object, source: str = "robot parameters") -> RobotParams:
        """The robot of :meth:`to_plain`'s mapping, validated; fields left out take their defaults.

        Raises
        ------
        InvalidParameterError
            Not a mapping, an unknown or missing field (the message names it and lists the
            fields), or a value the parameters refuse.
        """
        def fields_of(kind: type, plain: object, where: str) -> dict[str, object]:
            if not isinstance(plain, dict):
                raise InvalidParameterError(f"{where} must be a mapping of fields, got {type(plain).__name__!r}")
            known = [f.name for f in dataclasses.fields(kind)]
            unknown = sorted(str(k) for k in plain if k not in known)
            missing = [f.name for f in dataclasses.fields(kind) if f.name not in plain
                       and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
            if unknown or missing:
                raise InvalidParameterError(f"{where}: unknown field(s) {unknown!r}, missing field(s) {missing!r}; "
                                            f"the fields are {known!r}")
            return dict(plain)

        d = fields_of(cls, value, source)
        d["motor"] = MotorParams(**fields_of(MotorParams, d["motor"], f"{source}: motor"))
        return cls(**d)
