"""Robot and ground parameter presets, and the one import point of the parameter sets.

The parameter classes live in :mod:`energy.robot` (:class:`MotorParams`,
:class:`RobotParams`) and :mod:`energy.ground` (:class:`GroundParams`); this module
re-exports them beside the presets. Presets: :data:`ROBOT_PRESETS` (``"paper_seed"``,
``"jackal"``, ``"husky"``) and :data:`GROUND_PRESETS`; look them up with
:func:`robot_preset` / :func:`ground_preset`. Values tagged *estimate* in the preset
docstrings are plausible engineering values, not manufacturer data; issue 3 fits the
ground coefficients to logs.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from terrain import UNKNOWN_GROUND, TerrainMap
from terrawatt_base.errors import FileFormatError, InvalidParameterError, UnknownNameError
from terrawatt_base.formats import read_result_json, result_document, write_result_json

from .ground import GroundParams
from .robot import DRIVE_KINDS, GRAVITY_MPS2, MotorParams, RobotParams

__all__ = [
    "MotorParams",
    "RobotParams",
    "GroundParams",
    "DRIVE_KINDS",
    "GRAVITY_MPS2",
    "ROBOT_PRESETS",
    "GROUND_PRESETS",
    "robot_preset",
    "ground_preset",
    "robot_params",
    "robot_spec",
    "write_robot_file",
    "read_robot_file",
    "ROBOT_FILE_VERSION",
    "resolve_unknown_ground",
]


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
        # BorealTC: standing still, each side logs 0 or 0.59 A (the sensor's first step), whatever the
        # ground; 0.59 A is the median of the 478 rest samples of the shared logs (their mean 0.47 A)
        rest_current_a=0.59,
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


#: Format version of robot files (``terrawatt-robot``, :func:`write_robot_file`).
ROBOT_FILE_VERSION = 1


def write_robot_file(robot: RobotParams, path: str | os.PathLike[str]) -> Path:
    """Write ``robot`` as a robot file: JSON (format ``terrawatt-robot``, versioned), written atomically.

    Start from a preset and edit the numbers (SI units; :class:`RobotParams` says what each is),
    then give the file wherever a robot is named (its path, :func:`robot_params`).

    Raises
    ------
    InvalidParameterError
        ``robot`` is not a RobotParams.

    Examples
    --------
    >>> import tempfile
    >>> path = write_robot_file(robot_preset("jackal"), Path(tempfile.mkdtemp()) / "jackal.json")
    >>> read_robot_file(path) == robot_preset("jackal")
    True
    """
    if not isinstance(robot, RobotParams):
        raise InvalidParameterError(f"robot must be a RobotParams, got {type(robot).__name__!r}")
    return write_result_json(path, result_document("robot", ROBOT_FILE_VERSION, {"robot": robot.to_plain()}))


def read_robot_file(path: str | os.PathLike[str]) -> RobotParams:
    """The robot of a robot file (:func:`write_robot_file`), validated.

    Raises
    ------
    FileFormatError
        Missing, not JSON, not a robot file, or parameters the robot refuses (the message
        names the field).
    FormatVersionError
        Another format version.
    """
    document = read_result_json(path, "robot", ROBOT_FILE_VERSION)
    try:
        return RobotParams.from_plain(document.get("robot"), f"robot file {str(path)!r}")
    except (InvalidParameterError, TypeError) as exc:
        raise FileFormatError(f"robot file {str(path)!r} holds no valid robot: {exc}") from None


def robot_params(robot: str | os.PathLike[str] | RobotParams, *, name: str = "robot") -> RobotParams:
    """The robot that ``robot`` names: a :class:`RobotParams` as it is, a preset name
    (:data:`ROBOT_PRESETS`), or a robot file (a path ending in ``.json``, :func:`read_robot_file`).

    ``name`` is how messages call it: the caller's parameter, which the errors carry
    (:attr:`~terrawatt_base.errors.TerrawattError.parameter`).

    Raises
    ------
    InvalidParameterError
        Not a RobotParams, a string or a path.
    UnknownNameError
        Neither a preset name nor a ``.json`` path.
    FileFormatError, FormatVersionError
        As :func:`read_robot_file`.

    Examples
    --------
    >>> robot_params("husky") is robot_preset("husky"), robot_params(robot_preset("jackal")).name
    (True, 'jackal')
    """
    if isinstance(robot, RobotParams):
        return robot
    if not isinstance(robot, (str, os.PathLike)):
        raise InvalidParameterError(f"{name} must be a RobotParams, a preset name or a robot file (.json), got "
                                    f"{type(robot).__name__!r}", parameter=name)
    if isinstance(robot, str) and robot in ROBOT_PRESETS:
        return ROBOT_PRESETS[robot]
    if Path(robot).suffix.lower() == ".json":
        return read_robot_file(robot)
    raise UnknownNameError(f"{name} {robot!r:.80} is neither a robot preset ({', '.join(sorted(ROBOT_PRESETS))}) nor "
                           "a robot file (.json, energy.params.write_robot_file)", parameter=name)


def robot_spec(robot: str | os.PathLike[str] | RobotParams, *, name: str = "robot") -> str | RobotParams:
    """What a model keeps of a robot: a preset by its name (as model files record it), any other
    robot (a robot file, a RobotParams) by its parameters, never by a path a saved model would need.

    Raises
    ------
    InvalidParameterError, UnknownNameError, FileFormatError
        As :func:`robot_params`.

    Examples
    --------
    >>> robot_spec("husky"), robot_spec(robot_preset("jackal")).name
    ('husky', 'jackal')
    """
    if isinstance(robot, str) and robot in ROBOT_PRESETS:
        return robot
    return robot_params(robot, name=name)


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


def resolve_unknown_ground(name: str, terrain: TerrainMap | None) -> str | None:
    """The ground preset assumed on cells of unknown ground: ``name``, or None for ``"none"`` (refuse them).

    Parameters
    ----------
    name : str
        A ground preset name, or ``"none"`` (any case).
    terrain : TerrainMap or None
        The map it applies to; None for a map without ground classes (a DEM read by windows),
        whose every cell is of unknown ground.

    Returns
    -------
    str or None

    Raises
    ------
    UnknownNameError
        ``name`` is neither a ground preset nor ``"none"``.
    InvalidParameterError
        ``"none"`` where the map has cells of unknown ground. The errors' parameter is
        ``unknown_ground``.

    Examples
    --------
    >>> from terrain import flat_map
    >>> resolve_unknown_ground("sand", None), resolve_unknown_ground("none", flat_map((2, 2), 1.0, ground="ice"))
    ('sand', None)
    """
    flag = "unknown_ground"
    if not isinstance(name, str):
        raise UnknownNameError(f"{flag} must be a ground preset name or 'none', got {name!r}", parameter=flag)
    if name.lower() == "none":
        if terrain is None:
            raise InvalidParameterError(f"a GeoTIFF DEM has no ground classes, so {flag} none refuses every cell; give "
                                        f"{flag} NAME, one of {sorted(GROUND_PRESETS)!r}", parameter=flag)
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap or None, got {type(terrain).__name__}")
        n = int(np.count_nonzero(np.asarray(terrain.ground) == UNKNOWN_GROUND))
        if n:
            raise InvalidParameterError(
                f"the map's ground class is unknown in {n} of {terrain.ground.size} cells and {flag} none refuses "
                f"them; give {flag} NAME, one of {sorted(GROUND_PRESETS)!r}", parameter=flag)
        return None
    if name not in GROUND_PRESETS:
        raise UnknownNameError(f"{flag} must be a ground preset, one of {sorted(GROUND_PRESETS)!r}, or 'none'; "
                               f"got {name!r}", parameter=flag)
    return name
