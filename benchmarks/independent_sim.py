"""An independent Husky A200 log generator: its own skid-steer physics and BorealTC-like measurement.

This generator is written apart from the project's truth simulator (it shares no code and no
functional form with ``energy.sim`` or the diagnosis catalogue) so that the diagnosis can be
benchmarked on logs it was not built around. It produces :class:`energy.InteractionLog`
objects and writes them as CSV logs (:func:`energy.io.write_csv_log`) that
``terrawatt ... --data DIR`` reads.

Physics (SI, per side s in {L, R}, sigma_L = -1, sigma_R = +1), integrated on a 200 Hz grid:

- motion: the commanded (v, omega) are followed at bounded rates (the drive controller's
  limits ``ACCEL_LIMIT_MPS2``, ``ALPHA_LIMIT_RADPS2``), smoothed over ``SMOOTHING_S``; side speeds
  ``v_s = v + sigma_s chi B omega / 2`` (ICR expansion ``chi``, track ``B``).
- rolling resistance: ``F_roll,s = Crr m g / 2 * tanh(v_s / 0.01 m/s)``, Crr 0.03 (flooring
  with small wheels, plus the drag of knobby tyres and chains, lumped).
- inertia: ``F_in,s = m a / 2 + sigma_s I_z alpha / B + m_rot a_s`` with the yaw inertia
  ``I_z = m (L^2 + B^2) / 12`` (L wheelbase) and the rotating parts
  ``m_rot = (N^2 J_rotor + 2 J_wheel) / r^2`` per side.
- ``turning`` (Wong): ``mu_lat(R) = mu_max / (0.925 + 0.15 R / B)`` with the turn radius
  ``R = |v| / |omega|``; resistance moment ``M_r = mu_lat m g a`` (a = half wheelbase);
  it is balanced by a side-force couple ``F_turn,s = sigma_s M_r / B * tanh(omega / 0.01 rad/s)``
  — the outer side pushes, the inner side brakes; as the side speeds carry ``chi``, the
  turning power is ``chi M_r |omega|``.
- ``speed_friction``: a speed-*squared* resistance per side, ``F_sq,s = c_sq v_s |v_s|``
  (tyre hysteresis / drivetrain churning growing with v^2; neither static, Coulomb,
  Stribeck nor linear viscous).
- ``payload``: the mass ``m = 50 kg + payload`` in every mass term (rolling, inertia, yaw
  inertia, turning moment).
- ``slope`` (a :class:`Slope`, the ground the robot drives on: level when None): with the
  ground rising at ``theta`` along the uphill heading ``psi`` (a ramp between two distances
  along it, level before and after; a plane when unbounded), the pitch along the heading ``h``
  is ``atan(tan(theta) cos(h - psi))``; gravity pulls ``F_g,s = m g sin(pitch) / 2`` per side
  back down, and the normal force (rolling, turning) is ``m g cos(theta)``. The robot's pose is
  integrated from its true motion from ``start_pose``; standing still on a slope, the motors
  hold it (the current of the holding torque).
- DC motor per side, motoring only: wheel torque ``T_s = F_s r``; the motor current in the
  direction of rotation is ``I_s = max(T_s sign(v_s), 0) / (eta N K_t)``: a back-driven
  (braking) side logs an exact 0, its sensor offset included, as the Husky driver does (the
  BorealTC logs hold exact zeros in 0-41 % of a run's samples; a side standing still logs the offset).

Measurement (BorealTC-like, PHYSICS_NOTES "What the real logs show"):

- drive stream at ~6.5 Hz (jittered stamps): wheel-odometry ``v``, ``omega`` (velocity
  source ``"measured"``, ``track_width_m = chi B``) and the two currents;
- logged current ``offset + g_run,s g_case,s I_s + noise``, noise
  ``N(0, (0.08 A + 3 % I_s)^2)``, clipped at 0 and quantised to 0.13 A steps; the sensor
  offset (0.59 A) is in every sample, so a standing robot logs ~0.59 A per side; the
  per-run side gains ``g_run,s ~ N(1, 0.03^2)``; ``left_gain`` multiplies ``g_case,L``;
- IMU at 100 Hz: vertical acceleration ``g + vibration`` where the vibration is white noise
  of std ``0.03 + 0.25 |v| + 0.2 |omega|`` m/s^2 plus a tread tone of amplitude
  ``0.15 |v|`` at ``|v| n_lugs / (2 pi r)`` Hz; gyro yaw rate with a small bias and noise;
- ``lag``: the drive stream's stamps run ``drive_lag_s`` late against the IMU (the drive
  sample stamped t holds the motion and currents of ``t - drive_lag_s``);
- ``current_lag`` (a lag a current model can see, unlike ``lag``): the currents' stamps run ``current_lag_s``
  late against the speeds and the IMU (the sample stamped t holds the speeds of t and the
  currents of ``t - current_lag_s``).

Poses: with a ``slope`` or a ``start_pose`` the drive stream carries the true pose
(``pose_xyh``: x, y in m, heading in rad) at each sample, else none (as before).

Randomness: one :class:`numpy.random.SeedSequence` per run, spawned into separate streams
for the excitation, the current noise, the IMU and the run-level gains, so the same seed
with different effects drives the same manoeuvres with the same noise.

Usage::

    from independent_sim import CASES, simulate_run, write_runs
    logs = [simulate_run(seed, CASES["payload"]) for seed in range(6)]
    write_runs(logs, "out/payload")     # then: terrawatt diagnose --data out/payload ...
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from energy import InteractionLog, LogMeta, RobotParams, robot_preset
from energy.io import write_csv_log

__all__ = [
    "CASES",
    "DRIVING",
    "rotor_inertia_kg_m2",
    "husky_robot",
    "SimEffects",
    "Slope",
    "case_effects",
    "command_segments",
    "simulate_run",
    "write_runs",
]

# ---------------------------------------------------------------- Husky A200 (PHYSICS_NOTES, preset)
GRAVITY_MPS2 = 9.81
MASS_KG = 50.0  # Clearpath manual
WHEEL_RADIUS_M = 0.1651
TRACK_WIDTH_M = 0.555  # manual (URDF: 0.5708)
WHEELBASE_M = 0.512
ICR_EXPANSION = 1.875  # husky_control wheel_separation_multiplier
TORQUE_CONSTANT_NM_PER_A = 0.044  # the preset's estimate
GEAR_RATIO = 78.71  # the preset's estimate
GEAR_EFFICIENCY = 0.8  # the preset's estimate (gearbox + chain)
ROTOR_INERTIA_KG_M2 = 1.6e-5  # the preset's estimate
WHEEL_INERTIA_KG_M2 = 0.03  # own estimate: ~2.2 kg wheel, 0.5 m r^2

# ---------------------------------------------------------------- flooring-like hard ground (own values)
ROLLING_RESISTANCE_COEF = 0.03  # own: 0.015 (flooring, small wheels) + drag of knobby tyres and chains, lumped
ACCEL_LIMIT_MPS2 = 1.0  # the drive controller's acceleration limits
ALPHA_LIMIT_RADPS2 = 2.0
SMOOTHING_S = 0.1  # moving average after the rate limit

# ---------------------------------------------------------------- measurement
SIM_RATE_HZ = 200.0
DRIVE_RATE_HZ = 6.5
DRIVE_JITTER_S = 0.012
IMU_RATE_HZ = 100.0
IMU_JITTER_S = 0.0008
CURRENT_STEP_A = 0.13
REST_CURRENT_A = 0.59
CURRENT_NOISE_A = 0.08
CURRENT_NOISE_REL = 0.03
SIDE_GAIN_SPREAD = 0.03
ODOMETRY_NOISE_MPS = 0.003
ODOMETRY_NOISE_RADPS = 0.005
GYRO_NOISE_RADPS = 0.01
GYRO_BIAS_SPREAD_RADPS = 0.003
TREAD_LUGS = 30
#: Pre-roll at rest before t = 0 (s): room for a drive-stream lag of up to this much.
PAD_S = 1.0
#: Run length drawn uniformly from this range when not given (s).
DURATION_RANGE_S = (60.0, 90.0)


@dataclass(frozen=True)
class SimEffects:
    """Effects switched on in a run (the defaults: none).

    Parameters
    ----------
    payload_kg : float
        Extra mass carried (kg, >= 0).
    turning_mu_max : float
        Wong's peak lateral coefficient ``mu_max`` of the turning resistance; 0 switches
        turning resistance off.
    left_gain : float
        Factor on the left side's logged motor current (> 0).
    drive_lag_s : float
        How late the drive stream's stamps (speeds and currents) run against the IMU
        (s, |lag| < ``PAD_S``).
    current_lag_s : float
        How late the currents' stamps run against the speeds and the IMU (s, |lag| <
        ``PAD_S``): a lag between the motion and the current, not between the streams.
    speed_friction_n_s2_per_m2 : float
        ``c_sq`` of the speed-squared resistance per side (N s^2 / m^2, >= 0).
    rotor_inertia_scale : float
        Multiplies the rotating parts' inertia ``m_rot`` (> 0; e.g. a heavier wheel or gearbox).
    """

    payload_kg: float = 0.0
    turning_mu_max: float = 0.0
    left_gain: float = 1.0
    drive_lag_s: float = 0.0
    current_lag_s: float = 0.0
    speed_friction_n_s2_per_m2: float = 0.0
    rotor_inertia_scale: float = 1.0

    def __post_init__(self) -> None:
        checks = {
            "payload_kg": self.payload_kg >= 0.0,
            "turning_mu_max": self.turning_mu_max >= 0.0,
            "left_gain": self.left_gain > 0.0,
            "drive_lag_s": abs(self.drive_lag_s) < PAD_S,
            "current_lag_s": abs(self.drive_lag_s + self.current_lag_s) < PAD_S,
            "speed_friction_n_s2_per_m2": self.speed_friction_n_s2_per_m2 >= 0.0,
            "rotor_inertia_scale": self.rotor_inertia_scale > 0.0,
        }
        for name, ok in checks.items():
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and ok):
                raise ValueError(f"SimEffects.{name} is out of range: {value!r}")


@dataclass(frozen=True)
class Slope:
    """The ground the robot drives on: rising at ``angle_rad`` along ``uphill_heading_rad`` between the
    distances ``start_m`` and ``start_m + length_m`` along that heading from the origin, level before
    and after (a ramp up to a plateau); unbounded (the defaults), an inclined plane.

    Parameters
    ----------
    angle_rad : float
        Inclination of the ramp (rad, in [0, 30°]).
    uphill_heading_rad : float
        Direction in which the ground rises (rad, counter-clockwise from +x).
    start_m, length_m : float
        Where the ramp starts along the uphill heading (m, -inf: everywhere below) and its length
        (m, > 0, inf: everywhere above).

    Examples
    --------
    >>> ramp = Slope(math.radians(10.0), start_m=30.0, length_m=20.0)
    >>> [round(float(z), 3) for z in ramp.elevation_m(np.array([0.0, 40.0, 60.0]), np.zeros(3))]
    [0.0, 1.763, 3.527]
    """

    angle_rad: float
    uphill_heading_rad: float = 0.0
    start_m: float = -math.inf
    length_m: float = math.inf

    def __post_init__(self) -> None:
        checks = {
            "angle_rad": math.isfinite(self.angle_rad) and 0.0 <= self.angle_rad <= math.radians(30.0),
            "uphill_heading_rad": math.isfinite(self.uphill_heading_rad),
            "start_m": not math.isnan(self.start_m) and self.start_m < math.inf,
            "length_m": not math.isnan(self.length_m) and self.length_m > 0.0,
        }
        for name, ok in checks.items():
            if not ok:
                raise ValueError(f"Slope.{name} is out of range: {getattr(self, name)!r}")

    def _along(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        return x_m * math.cos(self.uphill_heading_rad) + y_m * math.sin(self.uphill_heading_rad)

    def on_ramp(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """Whether each point lies on the inclined part."""
        s = self._along(np.asarray(x_m, float), np.asarray(y_m, float))
        return (s >= self.start_m) & (s - self.start_m <= self.length_m)

    def elevation_m(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """Height of the ground at each point (m; 0 at the ramp's foot, or along the line through the
        origin across the heading for a plane)."""
        s = self._along(np.asarray(x_m, float), np.asarray(y_m, float))
        foot = self.start_m if math.isfinite(self.start_m) else 0.0
        return math.tan(self.angle_rad) * (np.clip(s, self.start_m, self.start_m + self.length_m) - foot)

    def pitch_rad(self, x_m: np.ndarray, y_m: np.ndarray, heading_rad: np.ndarray) -> np.ndarray:
        """Pitch along each heading at each point (rad, positive nose-up)."""
        grade = np.where(self.on_ramp(x_m, y_m), math.tan(self.angle_rad), 0.0)
        return np.arctan(grade * np.cos(np.asarray(heading_rad, float) - self.uphill_heading_rad))

    def cos_tilt(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """Cosine of the ground's inclination at each point (the share of the weight pressing on it)."""
        return np.where(self.on_ramp(x_m, y_m), math.cos(self.angle_rad), 1.0)


#: The benchmark's cases: one effect each (its default size), and ``none``.
CASES: dict[str, SimEffects] = {
    "none": SimEffects(),
    "payload": SimEffects(payload_kg=80.0),
    "turning": SimEffects(turning_mu_max=0.5),
    "left_gain": SimEffects(left_gain=1.25),
    "lag": SimEffects(drive_lag_s=0.35),
    "current_lag": SimEffects(current_lag_s=0.35),
    "speed_friction": SimEffects(speed_friction_n_s2_per_m2=15.0),
}
_CASE_FIELD = {
    "payload": "payload_kg",
    "turning": "turning_mu_max",
    "left_gain": "left_gain",
    "lag": "drive_lag_s",
    "current_lag": "current_lag_s",
    "speed_friction": "speed_friction_n_s2_per_m2",
}


def case_effects(spec: str) -> SimEffects:
    """The effects of a case name, optionally with its value: ``"payload"``, ``"payload:40"``.

    Raises
    ------
    KeyError
        An unknown case name.
    ValueError
        A value that is not a number, or a value given to ``none``.

    Examples
    --------
    >>> case_effects("payload:40").payload_kg
    40.0
    """
    name, _, value = spec.partition(":")
    if name not in CASES:
        raise KeyError(f"unknown case {name!r}; expected one of {sorted(CASES)!r}")
    if not value:
        return CASES[name]
    if name == "none":
        raise ValueError(f"case 'none' takes no value, got {spec!r}")
    return replace(CASES[name], **{_CASE_FIELD[name]: float(value)})


def rotor_inertia_kg_m2(scale: float = 1.0) -> float:
    """This simulator's rotating parts (``scale`` times its own) as the library's rotor inertia at the motor shaft.

    Its current ``m_rot a_s r / (eta N K_t)`` is the library's ``Jm N a_s / (r K_t)`` at
    ``Jm = m_rot r^2 / (eta N^2)`` (the wheels included; the library charges the rotor no gear loss):
    3.2e-5 kg m^2, twice the Husky preset's rotor alone.
    """
    m_rot = scale * (GEAR_RATIO**2 * ROTOR_INERTIA_KG_M2 + 2.0 * WHEEL_INERTIA_KG_M2) / WHEEL_RADIUS_M**2
    return m_rot * WHEEL_RADIUS_M**2 / (GEAR_EFFICIENCY * GEAR_RATIO**2)


def husky_robot() -> RobotParams:
    """The library's Husky preset with this simulator's drivetrain inertia (:func:`rotor_inertia_kg_m2`): what a
    user who knows the robot's rotating parts gives the physics model (the preset holds the rotor alone)."""
    rb = robot_preset("husky")
    return rb.replace(motor=replace(rb.motor, rotor_inertia_kg_m2=rotor_inertia_kg_m2()))


# ---------------------------------------------------------------------------- excitation
#: Segment kinds and their probabilities.
_KINDS = ("straight", "arc", "pivot", "stop")
#: Driving styles: the probabilities of straight, arc, pivot and stop segments.
DRIVING: dict[str, tuple[float, ...]] = {
    "mixed": (0.35, 0.25, 0.22, 0.18),
    "turning": (0.10, 0.45, 0.35, 0.10),  # turning-heavy: where a payload and a turning resistance look alike
    "straights": (0.90, 0.0, 0.0, 0.10),  # long straights: a payload and a rolling resistance look alike
    "pivots": (0.0, 0.0, 0.85, 0.15),  # turning on the spot only: a payload and a turning resistance look alike
    "cruise": (1.0, 0.0, 0.0, 0.0),  # one speed, no stops: a current gain and an offset look alike
    # straight, no stops, the speed swelling and easing smoothly between WAVE_SPEEDS_MPS: where the current
    # grows with the speed, its slope follows the acceleration, so a current lag and a drivetrain inertia look alike
    "waves": (1.0, 0.0, 0.0, 0.0),
}
#: The one speed of ``"cruise"`` driving (m/s).
CRUISE_SPEED_MPS = 0.6
#: ``"waves"`` driving: the range of its speeds (m/s), the length of one smooth change (s) and the hold
#: between the driver's small command steps (s; the controller's limits and smoothing make them one curve).
WAVE_SPEEDS_MPS = (0.25, 0.95)
WAVE_CHANGE_S = (8.0, 11.0)
WAVE_STEP_S = 0.05


def _wave_segments(duration_s: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``"waves"`` commands: a rest, one smooth start, then raised-cosine changes up and down in turn between
    random speeds in the top and bottom quarters of :data:`WAVE_SPEEDS_MPS`, each over :data:`WAVE_CHANGE_S`,
    commanded in steps of :data:`WAVE_STEP_S`; the last 1.5 s a stop."""
    t0 = float(rng.uniform(2.0, 3.0))
    end = duration_s - 1.5
    low, high = WAVE_SPEEDS_MPS
    band = 0.25 * (high - low)
    knots_t, knots_v = [t0], [0.0]
    t = t0
    while t < end:  # up and down in turn: each change spans most of the range
        t += float(rng.uniform(*WAVE_CHANGE_S))
        knots_t.append(min(t, end))
        up = len(knots_v) % 2 == 1
        knots_v.append(float(rng.uniform(high - band, high) if up else rng.uniform(low, low + band)))
    knots_v[-1] = min(knots_v[-1], WAVE_SPEEDS_MPS[0])  # ease down before the stop
    starts = np.arange(t0, end, WAVE_STEP_S)
    k = np.clip(np.searchsorted(knots_t, starts, side="right") - 1, 0, len(knots_t) - 2)
    kt, kv = np.asarray(knots_t), np.asarray(knots_v)
    phase = (starts - kt[k]) / (kt[k + 1] - kt[k])
    v = kv[k] + (kv[k + 1] - kv[k]) * 0.5 * (1.0 - np.cos(np.pi * phase))
    return (np.concatenate([[0.0], starts, [end]]), np.concatenate([[0.0], v, [0.0]]),
            np.zeros(starts.size + 2))


def command_segments(duration_s: float, rng: np.random.Generator,
                     driving: str = "mixed") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A teleoperation-like command schedule: (segment start times, v, omega).

    A rest of 2-3 s first (the standstill current), then straights at 0.2-0.9 m/s, arcs
    (0.3-0.7 m/s on 0.6-3 m radii), pivots (0.3-0.8 rad/s) and stops, left and right
    turns alike, until ``duration_s``; the last 1.5 s are a stop.

    Returns
    -------
    (start_s, v_mps, omega_radps) : arrays of equal length; command k holds from
    ``start_s[k]`` until the next start.
    """
    if driving == "waves":
        return _wave_segments(duration_s, rng)
    starts, vs, ws = [0.0], [0.0], [0.0]
    t = float(rng.uniform(2.0, 3.0))
    end = duration_s - 1.5
    while t < end:
        kind = _KINDS[int(rng.choice(len(_KINDS), p=DRIVING[driving]))]
        sign = 1.0 if rng.random() < 0.5 else -1.0
        if kind == "straight":
            v, w, d = rng.uniform(0.2, 0.9), 0.0, rng.uniform(4.0, 10.0)
            if driving == "cruise":
                v = CRUISE_SPEED_MPS
        elif kind == "arc":
            v = rng.uniform(0.3, 0.7)
            v, w, d = v, sign * v / rng.uniform(0.6, 3.0), rng.uniform(3.0, 7.0)
        elif kind == "pivot":
            v, w, d = 0.0, sign * rng.uniform(0.3, 0.8), rng.uniform(2.0, 5.0)
        else:
            v, w, d = 0.0, 0.0, rng.uniform(1.0, 3.0)
        starts.append(t)
        vs.append(v)
        ws.append(w)
        t += d
    starts.append(end)
    vs.append(0.0)
    ws.append(0.0)
    return np.asarray(starts), np.asarray(vs), np.asarray(ws)


def _ramped(starts: np.ndarray, target: np.ndarray, limit: float, grid: np.ndarray) -> np.ndarray:
    """Piecewise-constant commands followed at a bounded rate (the controller's acceleration
    limit), then smoothed by a ``SMOOTHING_S`` moving average (finite jerk, exact rests)."""
    y0 = np.zeros_like(target)  # value at each segment's start
    for k in range(1, target.size):  # one step per segment, not per sample
        span = starts[k] - starts[k - 1]
        step = target[k - 1] - y0[k - 1]
        y0[k] = y0[k - 1] + np.sign(step) * min(abs(step), limit * span)
    k = np.clip(np.searchsorted(starts, grid, side="right") - 1, 0, None)
    before = grid < starts[0]
    step = target[k] - y0[k]
    y = y0[k] + np.sign(step) * np.minimum(np.abs(step), limit * (grid - starts[k]))
    y = np.where(before, 0.0, y)
    n = max(int(round(SMOOTHING_S / (grid[1] - grid[0]))), 1)
    return np.convolve(np.pad(y, (n - 1, 0), mode="edge"), np.ones(n) / n, mode="valid")


# ---------------------------------------------------------------------------- physics
def _side_currents(v: np.ndarray, w: np.ndarray, dt_s: float, fx: SimEffects, pitch: Any = 0.0,
                   cos_tilt: Any = 1.0) -> tuple[np.ndarray, ...]:
    """Motor currents (A, in the direction of rotation: negative when back-driven) of the left and right sides
    on the simulation grid, on ground
    pitched by ``pitch`` (rad, along the heading) and inclined by ``arccos(cos_tilt)``."""
    m = MASS_KG + fx.payload_kg
    cos_tilt = np.asarray(cos_tilt, float)  # the share of the weight that is the normal force
    b = TRACK_WIDTH_M
    half_wheelbase = WHEELBASE_M / 2.0
    a = np.gradient(v, dt_s)
    alpha = np.gradient(w, dt_s)
    yaw_inertia = m * (WHEELBASE_M**2 + b**2) / 12.0
    m_rot = fx.rotor_inertia_scale * (GEAR_RATIO**2 * ROTOR_INERTIA_KG_M2 + 2.0 * WHEEL_INERTIA_KG_M2) / WHEEL_RADIUS_M**2
    if fx.turning_mu_max > 0.0:
        radius = np.abs(v) / np.maximum(np.abs(w), 1e-9)
        mu_lat = fx.turning_mu_max / (0.925 + 0.15 * radius / b)
        turn_couple = mu_lat * m * GRAVITY_MPS2 * cos_tilt * half_wheelbase / b * np.tanh(w / 0.01)
    else:
        turn_couple = np.zeros_like(v)
    out = []
    for sigma in (-1.0, 1.0):
        v_s = v + sigma * ICR_EXPANSION * b * w / 2.0
        a_s = a + sigma * ICR_EXPANSION * b * alpha / 2.0
        force = (
            0.5 * ROLLING_RESISTANCE_COEF * m * GRAVITY_MPS2 * cos_tilt * np.tanh(v_s / 0.01)
            + 0.5 * m * GRAVITY_MPS2 * np.sin(pitch)
            + 0.5 * m * a
            + sigma * yaw_inertia * alpha / b
            + m_rot * a_s
            + sigma * turn_couple
            + fx.speed_friction_n_s2_per_m2 * v_s * np.abs(v_s)
        )
        torque = force * WHEEL_RADIUS_M
        direction = np.where(np.abs(v_s) > 1e-3, np.sign(v_s), np.sign(torque))
        out.append(torque * direction / (GEAR_EFFICIENCY * GEAR_RATIO * TORQUE_CONSTANT_NM_PER_A))
    return out[0], out[1]


def _stamps(duration_s: float, rate_hz: float, jitter_s: float, rng: np.random.Generator) -> np.ndarray:
    """Jittered sample stamps in [0, duration_s], strictly increasing."""
    n = int(duration_s * rate_hz) + 1
    t = np.arange(n) / rate_hz + rng.uniform(-jitter_s, jitter_s, n)
    t[0] = 0.0
    return t[t <= duration_s]


def _quantise(current_a: np.ndarray) -> np.ndarray:
    return CURRENT_STEP_A * np.round(np.maximum(current_a, 0.0) / CURRENT_STEP_A)


def simulate_run(seed: int, effects: SimEffects = SimEffects(), duration_s: float | None = None,
                 *, ideal: bool = False, label: str = "", driving: str = "mixed",
                 commands: Any = None, slope: Slope | None = None,
                 start_pose: Sequence[float] | None = None) -> InteractionLog:
    """One simulated Husky run on flooring-like hard ground.

    Parameters
    ----------
    seed : int
        Seed of the run (excitation, noise, run-level gains).
    effects : SimEffects
        Effects switched on (default: none).
    duration_s : float, optional
        Length of the run (s); drawn from ``DURATION_RANGE_S`` when None.
    ideal : bool
        Leave out what no model can predict: current noise, quantisation and the per-run
        side gains (the offset stays); the same run otherwise (same stamps, manoeuvres,
        IMU), as the reference of the noise floor.
    label : str
        Case label written into ``meta.notes``.
    driving : str
        The driving style of the random commands, a key of :data:`DRIVING`.
    commands : CommandProfile, optional
        Drive these commands instead (an :class:`energy.CommandProfile`: the robot follows
        them within its controller's limits, as any command); the run then lasts as long as
        the profile and ``duration_s`` is ignored.
    slope : Slope, optional
        The ground driven on (default: level everywhere); its pitch under the robot's pose enters
        the physics.
    start_pose : (x_m, y_m, heading_rad), optional
        Where the run starts (default the origin, heading +x).

    Returns
    -------
    InteractionLog
        Drive stream ~6.5 Hz (measured v, omega; left/right currents; the true pose when a
        ``slope`` or a ``start_pose`` is given), IMU 100 Hz (vertical acceleration with gravity,
        gyro yaw rate);
        ``LogMeta(robot="husky", source="independent-sim", ground_label="flooring")``.

    Examples
    --------
    >>> log = simulate_run(0, duration_s=20.0)
    >>> f"{log.drive_rate_hz:.1f} Hz, {log.accel_rate_hz:.0f} Hz, {log.meta.ground_label}"
    '6.5 Hz, 100 Hz, flooring'
    """
    if not isinstance(effects, SimEffects):
        raise TypeError(f"effects must be a SimEffects, got {effects!r}")
    cmd_rng, cur_rng, imu_rng, run_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(4))
    if driving not in DRIVING:
        raise KeyError(f"unknown driving {driving!r}; expected one of {sorted(DRIVING)!r}")
    if slope is not None and not isinstance(slope, Slope):
        raise TypeError(f"slope must be a Slope or None, got {slope!r}")
    placed = slope is not None or start_pose is not None
    x0, y0, h0 = (0.0, 0.0, 0.0) if start_pose is None else (float(c) for c in start_pose)
    if not all(math.isfinite(c) for c in (x0, y0, h0)):
        raise ValueError(f"start_pose must be three finite numbers (x_m, y_m, heading_rad), got {start_pose!r}")
    if commands is not None:
        duration_s = float(commands.time_s[-1] - commands.time_s[0])
    if duration_s is None:
        duration_s = float(run_rng.uniform(*DURATION_RANGE_S))
    else:
        run_rng.uniform(*DURATION_RANGE_S)  # the same draws whether or not it is given
    if not (math.isfinite(duration_s) and duration_s >= (5.0 if commands is not None else 10.0)):
        raise ValueError(f"duration_s must be >= 10 s (5 s for a command profile), got {duration_s!r}")
    side_gain = run_rng.normal(1.0, SIDE_GAIN_SPREAD, 2)
    gyro_bias = run_rng.normal(0.0, GYRO_BIAS_SPREAD_RADPS)

    # motion and motor currents on a fine grid from -PAD_S (at rest) to the end
    dt = 1.0 / SIM_RATE_HZ
    grid = np.arange(-PAD_S, duration_s + PAD_S + dt, dt)
    if commands is None:
        starts, v_cmd, w_cmd = command_segments(duration_s, cmd_rng, driving)
    else:  # the profile's samples as holds (its own ramps are kept: each sample is a short segment)
        starts = np.asarray(commands.time_s, float) - float(commands.time_s[0])
        v_cmd, w_cmd = np.asarray(commands.v_mps, float), np.asarray(commands.omega_radps, float)
    v = _ramped(starts, v_cmd, ACCEL_LIMIT_MPS2, grid)
    w = _ramped(starts, w_cmd, ALPHA_LIMIT_RADPS2, grid)
    heading = h0 + np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * dt)])
    x = x0 + np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt * np.cos(heading[:-1]))])
    y = y0 + np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt * np.sin(heading[:-1]))])
    if slope is None:
        pitch, cos_tilt = np.zeros_like(v), np.ones_like(v)
    else:
        pitch, cos_tilt = slope.pitch_rad(x, y, heading), slope.cos_tilt(x, y)
    i_left, i_right = _side_currents(v, w, dt, effects, pitch, cos_tilt)

    # drive stream: stamps late by drive_lag_s against the motion (and the IMU)
    td = _stamps(duration_s, DRIVE_RATE_HZ, DRIVE_JITTER_S, cur_rng)
    t_true = td - effects.drive_lag_s
    gains = (np.ones(2) if ideal else side_gain) * np.array([effects.left_gain, 1.0])
    logged = []
    for g, i_side in zip(gains, (i_left, i_right)):
        signed = np.interp(t_true - effects.current_lag_s, grid, i_side)
        i_s = np.maximum(signed, 0.0)
        noise = cur_rng.normal(0.0, 1.0, td.size) * (CURRENT_NOISE_A + CURRENT_NOISE_REL * i_s)
        reading = REST_CURRENT_A + g * i_s
        # a back-driven side logs an exact 0, its sensor offset included (the real logs' zeros)
        logged.append(np.where(signed < 0.0, 0.0, reading if ideal else _quantise(reading + noise)))
    v_log = np.interp(t_true, grid, v) + cur_rng.normal(0.0, ODOMETRY_NOISE_MPS, td.size)
    w_log = np.interp(t_true, grid, w) + cur_rng.normal(0.0, ODOMETRY_NOISE_RADPS, td.size)
    pose = (np.column_stack([np.interp(t_true, grid, q) for q in (x, y, heading)]) if placed else None)

    # IMU stream on the true clock
    ta = _stamps(duration_s, IMU_RATE_HZ, IMU_JITTER_S, imu_rng)
    v_a = np.abs(np.interp(ta, grid, v))
    w_a = np.interp(ta, grid, w)
    tread_hz = v_a * TREAD_LUGS / (2.0 * np.pi * WHEEL_RADIUS_M)
    phase = 2.0 * np.pi * np.concatenate([[0.0], np.cumsum(0.5 * (tread_hz[1:] + tread_hz[:-1]) * np.diff(ta))])
    vib_std = 0.03 + 0.25 * v_a + 0.2 * np.abs(w_a)
    accel_z = GRAVITY_MPS2 * np.interp(ta, grid, cos_tilt) + vib_std * imu_rng.normal(0.0, 1.0, ta.size) + 0.15 * v_a * np.sin(phase)
    gyro = w_a + gyro_bias + imu_rng.normal(0.0, GYRO_NOISE_RADPS, ta.size)

    notes = f"independent Husky simulator, seed {seed}" + (f", case {label}" if label else "")
    return InteractionLog(
        time_s=td, v_mps=v_log, omega_radps=w_log, current_left_a=logged[0], current_right_a=logged[1],
        accel_time_s=ta, accel_z_mps2=accel_z, gyro_z_radps=gyro, pose_xyh=pose,
        meta=LogMeta(robot="husky", source="independent-sim", ground_label="flooring", velocity_source="measured",
                     track_width_m=ICR_EXPANSION * TRACK_WIDTH_M, notes=notes),
    )


def write_runs(logs: Sequence[InteractionLog], folder: str | os.PathLike[str], prefix: str = "run") -> list[Path]:
    """Write logs as CSV files ``{prefix}_00.csv``, ... in ``folder`` (created); return the paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    return [write_csv_log(log, folder / f"{prefix}_{k:02d}.csv") for k, log in enumerate(logs)]
