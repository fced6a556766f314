"""Truth simulator: synthetic interaction logs from the physics model, noise and ground vibration.

:class:`TruthSimulator` turns velocity commands (on the spot, :meth:`~TruthSimulator.simulate_commands`)
or a route over a :class:`~terrain.TerrainMap` (:meth:`~TruthSimulator.drive`) into an
:class:`~energy.logs.InteractionLog` that looks like a real robot's:

1. **Velocity tracking.** The drive follows the commands with a first-order lag
   (time constant ``velocity_time_constant_s``; ``scipy.signal.lfilter``); the robot is in
   steady motion at the first command when the record starts. Accelerations are the
   backward differences of the tracked velocities.
2. **Drive currents.** :class:`~energy.physics.PhysicsEnergyModel` (``effects`` switch its
   effects, so a log can hold an effect that a model under test lacks) gives the signed
   motor current ``I`` and motor speed ``omega_m`` of each side for the tracked motion, the
   slope along the heading and the ground of every sample. The logged current is the
   *motoring* current, ``I * sign(omega_m)`` (``|I|`` at ``omega_m = 0``): positive while
   the motor drives its wheels in either direction, negative while it is back-driven
   (braking). This is what the Husky driver reports in BorealTC: both sides draw current in
   a pivot turn and in reverse, the braked inner side of an arc reads 0.
3. **Ground variation** (optional, :class:`GroundVariation` per ground): a smooth random
   field over the distance travelled by the wheels scales the ground's resistance
   coefficients (rolling, viscous, lateral friction) — patchy snow, varying grass — and
   the broadband vibration with it.
4. **Measurement** (:class:`NoiseModel`): per-run side gains, idle current, Gaussian noise,
   positive outlier spikes, clipping of braking currents to 0 and quantisation.
5. **Vertical vibration**: gravity ``g cos(tilt)`` plus, per ground, narrow spectral peaks
   (:class:`VibrationSignature`: frequencies, amplitudes growing with the wheel speed,
   optional speed-proportional shift for periodic ground such as tile joints) and a
   broadband roughness, plus accelerometer noise, at the IMU's own rate and timestamps.

Every random component draws from its own stream of ``numpy.random.SeedSequence(seed)``,
so the same seed gives the same log and switching one component off leaves the others'
draws unchanged. Presets: :data:`PAPER_GROUNDS` (the vibration-current paper's three
grounds), :data:`VIBRATION_PRESETS` (one signature per ground preset and paper ground; the
values are plausible, invented ones shaped after the paper's Fig. 7 and the BorealTC
IMU spectra — not measurements), :data:`PAPER_VARIATION`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import ndimage, signal

from terrain.errors import (
    BlockedPositionError,
    InvalidParameterError,
    UnknownNameError,
)
from terrain.terrain_map import UNKNOWN_GROUND, TerrainMap

from .commands import CommandProfile, command_series, uniform_step_s
from .profiles import waypoint_commands
from .logs import InteractionLog, LogMeta
from .params import GRAVITY_MPS2, GroundParams, RobotParams, ground_preset
from .physics import EFFECTS, PhysicsEnergyModel, PowerBreakdown

__all__ = [
    "VibrationSignature",
    "NoiseModel",
    "GroundVariation",
    "TruthRun",
    "TruthSimulator",
    "PAPER_GROUNDS",
    "PAPER_VARIATION",
    "VIBRATION_PRESETS",
    "vibration_preset",
]

_LOG = logging.getLogger(__name__)

# Resolution of the quantised resistance factor of ground variation (in log units).
_FACTOR_LOG_STEP = 0.005
# Independent random streams, in spawn order of SeedSequence(seed).
_STREAMS = ("current_noise", "outliers", "side_gain", "variation", "vibration", "accel_noise")


def _real(owner: str, name: str, value: Any, *, low: float | None = 0.0, strict: bool = False,
          high: float | None = None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InvalidParameterError(f"{owner}.{name} must be a real number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise InvalidParameterError(f"{owner}.{name} must be finite, got {value!r}")
    if low is not None and (v < low or (strict and v == low)):
        raise InvalidParameterError(f"{owner}.{name} must be {'>' if strict else '>='} {low!r}, got {value!r}")
    if high is not None and v > high:
        raise InvalidParameterError(f"{owner}.{name} must be <= {high!r}, got {value!r}")
    return v


def _real_tuple(owner: str, name: str, values: Any) -> tuple[float, ...]:
    try:
        items = tuple(values)
    except TypeError:
        raise InvalidParameterError(f"{owner}.{name} must be a sequence of numbers, got {values!r}") from None
    return tuple(_real(owner, f"{name}[{k}]", v) for k, v in enumerate(items))


# ============================================================================ parameters
@dataclass(frozen=True, kw_only=True)
class VibrationSignature:
    """Vertical-vibration spectrum of one ground as a function of the wheel speed.

    The wheel speed ``s`` is the mean absolute side speed of the ICR kinematics,
    ``max(|v|, |omega| * chi * B / 2)`` (a pivot turn shakes the robot too). At speed ``s``
    peak ``k`` is a narrow line at ``f_k + shift_k * s`` Hz with amplitude
    ``A_k * (s / s_ref) ** p`` (m/s^2, a sinusoid's amplitude: RMS ``A_k / sqrt 2``) and a
    Lorentzian width ``peak_width_hz`` (random phase diffusion); the broadband roughness is
    Gaussian noise of RMS ``roughness_mps2 * (s / s_ref) ** p``, white up to the Nyquist
    frequency or first-order low-passed at ``roughness_corner_hz``. At rest (``s = 0``) the
    ground adds nothing.

    Parameters
    ----------
    peak_frequencies_hz : tuple of float
        ``f_k`` (>= 0), Hz.
    peak_amplitudes_mps2 : tuple of float
        ``A_k`` (>= 0) at the reference speed, m/s^2; one per peak.
    peak_shifts_hz_per_mps : tuple of float or None
        ``shift_k`` (>= 0), Hz per m/s; ``None`` = all zero. A periodic ground of spatial
        period ``L`` (tile joints) is a peak with ``f_k = 0`` and ``shift_k = 1 / L``.
    peak_width_hz : float
        Full width at half maximum of every peak (>= 0; 0 = pure tones), Hz.
    roughness_mps2 : float
        Broadband RMS (>= 0) at the reference speed, m/s^2.
    roughness_corner_hz : float or None
        Corner of the roughness low-pass (> 0), Hz; ``None`` = white.
    reference_speed_mps : float
        ``s_ref`` (> 0), m/s.
    speed_exponent : float
        ``p`` (>= 0): how the amplitudes grow with speed (1 = proportional).

    Raises
    ------
    InvalidParameterError
        Negative or non-finite values, peak tuples of different lengths.

    Examples
    --------
    >>> sig = VibrationSignature(peak_frequencies_hz=(12.0,), peak_amplitudes_mps2=(0.2,))
    >>> float(sig.amplitude_scale(0.8)), sig.peak_frequencies_at(0.8)
    (2.0, (12.0,))
    """

    peak_frequencies_hz: tuple[float, ...] = ()
    peak_amplitudes_mps2: tuple[float, ...] = ()
    peak_shifts_hz_per_mps: tuple[float, ...] | None = None
    peak_width_hz: float = 0.5
    roughness_mps2: float = 0.0
    roughness_corner_hz: float | None = None
    reference_speed_mps: float = 0.4
    speed_exponent: float = 1.0

    def __post_init__(self) -> None:
        own = "VibrationSignature"
        freqs = _real_tuple(own, "peak_frequencies_hz", self.peak_frequencies_hz)
        amps = _real_tuple(own, "peak_amplitudes_mps2", self.peak_amplitudes_mps2)
        if len(amps) != len(freqs):
            raise InvalidParameterError(
                f"{own}.peak_amplitudes_mps2 must have one entry per peak ({len(freqs)}), got {len(amps)}"
            )
        shifts = (0.0,) * len(freqs) if self.peak_shifts_hz_per_mps is None else _real_tuple(
            own, "peak_shifts_hz_per_mps", self.peak_shifts_hz_per_mps)
        if len(shifts) != len(freqs):
            raise InvalidParameterError(
                f"{own}.peak_shifts_hz_per_mps must have one entry per peak ({len(freqs)}), got {len(shifts)}"
            )
        object.__setattr__(self, "peak_frequencies_hz", freqs)
        object.__setattr__(self, "peak_amplitudes_mps2", amps)
        object.__setattr__(self, "peak_shifts_hz_per_mps", shifts)
        _real(own, "peak_width_hz", self.peak_width_hz)
        _real(own, "roughness_mps2", self.roughness_mps2)
        if self.roughness_corner_hz is not None:
            _real(own, "roughness_corner_hz", self.roughness_corner_hz, strict=True)
        _real(own, "reference_speed_mps", self.reference_speed_mps, strict=True)
        _real(own, "speed_exponent", self.speed_exponent)

    def amplitude_scale(self, speed_mps: Any) -> np.ndarray:
        """``(s / s_ref) ** p`` for wheel speeds ``s`` (0 where ``s == 0``)."""
        s = np.abs(np.asarray(speed_mps, dtype=np.float64))
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.where(s > 0, (s / self.reference_speed_mps) ** self.speed_exponent, 0.0)
        return out

    def peak_frequencies_at(self, speed_mps: float) -> tuple[float, ...]:
        """Peak frequencies (Hz) at a constant wheel speed."""
        s = abs(float(speed_mps))
        return tuple(f + k * s for f, k in zip(self.peak_frequencies_hz, self.peak_shifts_hz_per_mps))

    def rms_mps2(self, speed_mps: float) -> float:
        """Expected RMS of the ground's vibration at a constant wheel speed (m/s^2)."""
        scale = float(self.amplitude_scale(speed_mps))
        power = self.roughness_mps2**2 + sum(a * a / 2.0 for a in self.peak_amplitudes_mps2)
        return scale * math.sqrt(power)


@dataclass(frozen=True, kw_only=True)
class NoiseModel:
    """How the drive currents and the accelerometer are measured.

    The logged current of a side is, in this order: ``gain * (I_motoring + idle)`` plus
    Gaussian noise, plus outlier spikes; braking (negative) values set to 0 when
    ``clip_negative``; rounded to multiples of ``quantisation_step_a``.

    Parameters
    ----------
    current_noise_std_a : float
        Standard deviation of white Gaussian current noise (>= 0), A.
    outlier_rate : float
        Fraction of samples (per side) with an outlier spike, in [0, 1].
    outlier_magnitude_a : float
        Typical spike (>= 0), A; each spike is positive and uniform in [0.5, 1.5] times it.
    quantisation_step_a : float
        Resolution of the current sensor (>= 0; 0 = none), A. BorealTC's Husky logs show
        steps of about 0.13 A.
    idle_current_a : float
        Current drawn by a standing drive (>= 0), A (BorealTC: about 0.59 A).
    clip_negative : bool
        Report braking currents as 0, like the Husky driver.
    side_gain_std : float
        Log-normal spread (>= 0) of a per-run gain of each side's current (calibration,
        wear); 0 = exact.
    accel_noise_std_mps2 : float
        Standard deviation of white accelerometer noise (>= 0), m/s^2.

    Raises
    ------
    InvalidParameterError
        Negative or non-finite values, a rate outside [0, 1].
    """

    current_noise_std_a: float = 0.1
    outlier_rate: float = 0.002
    outlier_magnitude_a: float = 2.0
    quantisation_step_a: float = 0.13
    idle_current_a: float = 0.59
    clip_negative: bool = True
    side_gain_std: float = 0.0
    accel_noise_std_mps2: float = 0.02

    def __post_init__(self) -> None:
        own = "NoiseModel"
        for name in ("current_noise_std_a", "outlier_magnitude_a", "quantisation_step_a",
                     "idle_current_a", "side_gain_std", "accel_noise_std_mps2"):
            _real(own, name, getattr(self, name))
        _real(own, "outlier_rate", self.outlier_rate, high=1.0)
        if not isinstance(self.clip_negative, bool):
            raise InvalidParameterError(f"{own}.clip_negative must be a bool, got {self.clip_negative!r}")

    @classmethod
    def off(cls) -> NoiseModel:
        """No noise, outliers, quantisation, idle current, clipping or gains: the logged
        currents are the physics model's motoring currents, the acceleration has no sensor
        noise."""
        return cls(current_noise_std_a=0.0, outlier_rate=0.0, outlier_magnitude_a=0.0,
                   quantisation_step_a=0.0, idle_current_a=0.0, clip_negative=False,
                   side_gain_std=0.0, accel_noise_std_mps2=0.0)


@dataclass(frozen=True, kw_only=True)
class GroundVariation:
    """Slow, random variation of one ground's resistance along the path.

    A stationary Gaussian field ``z`` (unit variance, Gaussian smoothing of standard
    deviation ``length_scale_m`` over the distance travelled by the wheels) gives the
    factor ``exp(relative_std * z - relative_std**2 / 2)`` (mean 1), which multiplies the
    ground's rolling resistance, viscous and lateral friction coefficients (quantised to
    0.5 % steps), and raised to ``vibration_coupling`` its broadband roughness.

    Parameters
    ----------
    relative_std : float
        Log-normal spread of the factor (>= 0; 0.1 is about +/-10 %).
    length_scale_m : float
        Correlation length (> 0), m of wheel travel.
    vibration_coupling : float
        Exponent (>= 0) of the factor on the roughness amplitude (0 = vibration unaffected).

    Raises
    ------
    InvalidParameterError
        Negative or non-finite values.
    """

    relative_std: float
    length_scale_m: float = 2.0
    vibration_coupling: float = 1.0

    def __post_init__(self) -> None:
        own = "GroundVariation"
        _real(own, "relative_std", self.relative_std, high=2.0)
        _real(own, "length_scale_m", self.length_scale_m, strict=True)
        _real(own, "vibration_coupling", self.vibration_coupling)


# ============================================================================== presets
def _snow_over(name: str, mu_s: float, mu_k: float, crr: float, c_v: float, mu_lat: float) -> GroundParams:
    return GroundParams(name=name, static_friction_coef=mu_s, coulomb_friction_coef=mu_k,
                        stribeck_velocity_coef_s_per_m=20.0, viscous_friction_coef_s_per_m=c_v,
                        rolling_resistance_coef=crr, lateral_friction_coef=mu_lat,
                        longitudinal_slip_coef=0.06, lateral_slip_coef=0.08)


#: The vibration-current paper's three grounds. ``"coated_wood"`` is the library preset;
#: the two thin-snow grounds are estimates between the ``"snow"`` preset and the hard
#: surface underneath (more rolling resistance and less lateral grip than the bare
#: surface; tiles slightly rougher than concrete).
PAPER_GROUNDS: dict[str, GroundParams] = {
    "coated_wood": ground_preset("coated_wood"),
    "snow_over_stone_tiles": _snow_over("snow_over_stone_tiles", 0.45, 0.35, 0.045, 0.015, 0.35),
    "snow_over_concrete": _snow_over("snow_over_concrete", 0.40, 0.30, 0.040, 0.012, 0.30),
}

#: Ground variation of the paper's grounds (estimates): varnished wood is uniform, a thin
#: snow layer is patchy.
PAPER_VARIATION: dict[str, GroundVariation] = {
    "coated_wood": GroundVariation(relative_std=0.03, length_scale_m=3.0),
    "snow_over_stone_tiles": GroundVariation(relative_std=0.15, length_scale_m=1.5),
    "snow_over_concrete": GroundVariation(relative_std=0.20, length_scale_m=1.5),
}


def _sig(freqs: tuple[float, ...], amps: tuple[float, ...], rough: float, *,
         shifts: tuple[float, ...] | None = None, corner: float | None = None,
         width: float = 0.5) -> VibrationSignature:
    return VibrationSignature(peak_frequencies_hz=freqs, peak_amplitudes_mps2=amps,
                              peak_shifts_hz_per_mps=shifts, peak_width_hz=width,
                              roughness_mps2=rough, roughness_corner_hz=corner)


#: Vibration signatures by ground name (every :data:`~energy.params.GROUND_PRESETS` name and
#: every :data:`PAPER_GROUNDS` name), at the reference wheel speed 0.4 m/s. Invented but
#: plausible: RMS of 0.1–1 m/s^2 as in BorealTC's Husky IMU (flooring ~0.4, snow ~1.2 m/s^2
#: at ~0.2 m/s), hard smooth grounds with sharp structural peaks and little roughness,
#: soft grounds damped above a corner frequency, tiles with a joint-passing line
#: (0.3 m tiles: 3.33 Hz per m/s).
VIBRATION_PRESETS: dict[str, VibrationSignature] = {
    "asphalt": _sig((9.0, 18.0), (0.25, 0.15), 0.35),
    "concrete": _sig((10.0, 21.0), (0.20, 0.10), 0.25),
    "stone": _sig((7.0, 15.0), (0.35, 0.20), 0.50),
    "flooring": _sig((8.0, 14.0), (0.25, 0.20), 0.12),
    "coated_wood": _sig((11.0, 24.0), (0.15, 0.08), 0.10),
    "gravel": _sig((6.0, 27.0), (0.40, 0.20), 0.90),
    "grass": _sig((4.0,), (0.20,), 0.30, corner=15.0),
    "sand": _sig((3.0,), (0.15,), 0.25, corner=10.0),
    "snow": _sig((5.0, 12.0), (0.30, 0.20), 0.80, corner=20.0),
    "ice": _sig((10.0,), (0.10,), 0.08),
    "snow_over_stone_tiles": _sig((0.0, 7.5, 17.0), (0.50, 0.35, 0.25), 0.60,
                                  shifts=(1.0 / 0.3, 0.0, 0.0), corner=25.0),
    "snow_over_concrete": _sig((5.5, 14.0, 31.0), (0.30, 0.20, 0.10), 0.70, corner=20.0),
}


def vibration_preset(name: str) -> VibrationSignature:
    """The vibration signature preset of the ground called ``name``.

    Raises
    ------
    UnknownNameError
        ``name`` is not a key of :data:`VIBRATION_PRESETS` (the message lists them).

    Examples
    --------
    >>> vibration_preset("coated_wood").peak_frequencies_hz
    (11.0, 24.0)
    """
    try:
        return VIBRATION_PRESETS[name]
    except (KeyError, TypeError):
        raise UnknownNameError(
            f"vibration preset {name!r} is unknown; expected one of {sorted(VIBRATION_PRESETS)!r}"
        ) from None


# ================================================================================ result
@dataclass(frozen=True, eq=False)
class TruthRun:
    """A synthesised log with the noise-free truth behind it.

    Attributes
    ----------
    log : InteractionLog
        What a robot would have recorded (commands, measured currents, acceleration).
    breakdown : PowerBreakdown
        The physics model's output for the tracked motion (battery power, signed motor
        currents, per-effect components).
    actual_v_mps, actual_omega_radps : numpy.ndarray, shape (N,)
        Tracked (lagged) speed and yaw rate.
    accel_mps2, alpha_radps2 : numpy.ndarray, shape (N,)
        Their time derivatives as fed to the physics model.
    slope_rad : numpy.ndarray, shape (N,)
        Pitch along the heading (positive uphill).
    resistance_factor : numpy.ndarray, shape (N,)
        Ground-variation factor on the resistance coefficients (1 without variation).
    clean_current_a : numpy.ndarray, shape (N, 2)
        ``[left, right]`` current as the sensor would read it without noise, outliers and
        quantisation (gains, idle and clipping applied), A.
    """

    log: InteractionLog
    breakdown: PowerBreakdown
    actual_v_mps: np.ndarray
    actual_omega_radps: np.ndarray
    accel_mps2: np.ndarray
    alpha_radps2: np.ndarray
    slope_rad: np.ndarray
    resistance_factor: np.ndarray
    clean_current_a: np.ndarray

    def __post_init__(self) -> None:
        n = len(self.log)
        for name in ("actual_v_mps", "actual_omega_radps", "accel_mps2", "alpha_radps2", "slope_rad",
                     "resistance_factor", "clean_current_a"):
            arr = np.array(getattr(self, name), dtype=np.float64)
            expected = (n, 2) if name == "clean_current_a" else (n,)
            if arr.shape != expected:
                raise InvalidParameterError(f"TruthRun.{name} must have shape {expected!r}, got {arr.shape!r}")
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if self.breakdown.n_samples != n:
            raise InvalidParameterError(
                f"TruthRun.breakdown must have {n} samples like the log, got {self.breakdown.n_samples}"
            )


# ============================================================================= simulator
def _check_seed(seed: Any) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidParameterError(f"seed must be an int >= 0, got {seed!r}")
    return int(seed)


class TruthSimulator:
    """Synthesise interaction logs of a robot on named grounds, seeded.

    Parameters
    ----------
    robot : RobotParams
        The robot.
    grounds : mapping of str to GroundParams
        The grounds by name; the names are the labels of commands, logs and the map's
        ground classes.
    effects : iterable of str, optional
        Physics effects of the truth (names from :data:`~energy.physics.EFFECTS`);
        ``None`` = all. Passed to :class:`~energy.physics.PhysicsEnergyModel`.
    vibration : mapping of str to VibrationSignature, optional
        Signature of each ground (extra keys are ignored); ``None`` takes
        :data:`VIBRATION_PRESETS` by ground name.
    noise : NoiseModel
        Measurement model (default ``NoiseModel()``; ``NoiseModel.off()`` for clean logs).
    variation : mapping of str to GroundVariation, optional
        Ground variation by ground name; grounds without an entry are uniform.
    velocity_time_constant_s : float
        Time constant (>= 0) of the first-order velocity tracking; 0 = commands are
        followed exactly.
    current_rate_hz : float
        Drive-stream rate of :meth:`drive` (> 0), Hz.
    accel_rate_hz : float
        IMU rate (> 0), Hz; at least twice every vibration peak frequency.
    seed : int
        Default seed (>= 0) of every method; each method takes its own ``seed=`` too.

    Raises
    ------
    InvalidParameterError
        Bad types or values.
    UnknownNameError
        An unknown effect, or a ground without a vibration signature.

    Examples
    --------
    >>> from energy import robot_preset
    >>> sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS, seed=0)
    >>> log = sim.simulate_commands([0.0, 0.01, 0.02], [0.4] * 3, [0.0] * 3, ground="coated_wood")
    >>> len(log), log.meta.ground_label
    (3, 'coated_wood')
    """

    def __init__(
        self,
        robot: RobotParams,
        grounds: Mapping[str, GroundParams],
        effects: Sequence[str] | None = None,
        vibration: Mapping[str, VibrationSignature] | None = None,
        noise: NoiseModel = NoiseModel(),
        *,
        variation: Mapping[str, GroundVariation] | None = None,
        velocity_time_constant_s: float = 0.1,
        current_rate_hz: float = 100.0,
        accel_rate_hz: float = 100.0,
        seed: int = 0,
    ) -> None:
        self.model = PhysicsEnergyModel(robot, effects)
        self.robot = robot
        if not isinstance(grounds, Mapping) or not grounds:
            raise InvalidParameterError(f"grounds must be a non-empty mapping of name to GroundParams, got {grounds!r:.80}")
        for name, g in grounds.items():
            if not isinstance(name, str) or not name:
                raise InvalidParameterError(f"ground names must be non-empty str, got {name!r}")
            if not isinstance(g, GroundParams):
                raise InvalidParameterError(f"grounds[{name!r}] must be a GroundParams, got {type(g).__name__!r}")
        self.grounds: dict[str, GroundParams] = dict(grounds)
        self._names: tuple[str, ...] = tuple(self.grounds)
        source = VIBRATION_PRESETS if vibration is None else vibration
        if not isinstance(source, Mapping):
            raise InvalidParameterError(f"vibration must be a mapping of ground name to VibrationSignature, got {vibration!r:.80}")
        missing = [n for n in self._names if n not in source]
        if missing:
            where = "VIBRATION_PRESETS" if vibration is None else "vibration"
            raise UnknownNameError(
                f"no vibration signature for ground(s) {missing!r} in {where}; known: {sorted(source)!r} "
                "(pass vibration={name: VibrationSignature(...)})"
            )
        for n in self._names:
            if not isinstance(source[n], VibrationSignature):
                raise InvalidParameterError(f"vibration[{n!r}] must be a VibrationSignature, got {type(source[n]).__name__!r}")
        self.vibration: dict[str, VibrationSignature] = {n: source[n] for n in self._names}
        if not isinstance(noise, NoiseModel):
            raise InvalidParameterError(f"noise must be a NoiseModel, got {type(noise).__name__!r}")
        self.noise = noise
        var = {} if variation is None else variation
        if not isinstance(var, Mapping):
            raise InvalidParameterError(f"variation must be a mapping of ground name to GroundVariation, got {variation!r:.80}")
        for n, v in var.items():
            if not isinstance(v, GroundVariation):
                raise InvalidParameterError(f"variation[{n!r}] must be a GroundVariation, got {type(v).__name__!r}")
        self.variation: dict[str, GroundVariation] = {n: var[n] for n in self._names if n in var}
        own = "TruthSimulator"
        self.velocity_time_constant_s = _real(own, "velocity_time_constant_s", velocity_time_constant_s)
        self.current_rate_hz = _real(own, "current_rate_hz", current_rate_hz, strict=True)
        self.accel_rate_hz = _real(own, "accel_rate_hz", accel_rate_hz, strict=True)
        nyquist = self.accel_rate_hz / 2.0
        for n, sig in self.vibration.items():
            if any(f >= nyquist for f in sig.peak_frequencies_hz):
                raise InvalidParameterError(
                    f"vibration[{n!r}] has peaks at {sig.peak_frequencies_hz!r} Hz, not below the IMU's Nyquist "
                    f"frequency {nyquist!r} Hz (accel_rate_hz={self.accel_rate_hz!r})"
                )
        self.seed = _check_seed(seed)

    def __repr__(self) -> str:
        return (f"TruthSimulator(robot={self.robot.name!r}, grounds={list(self._names)!r}, "
                f"effects={len(self.model.effects)} of the physics model's, seed={self.seed})")

    @property
    def effects(self) -> tuple[str, ...]:
        """The physics effects of the truth."""
        return self.model.effects

    @property
    def ground_names(self) -> tuple[str, ...]:
        """The ground names, in the order given."""
        return self._names

    # ---------------------------------------------------------------- public
    def run_commands(
        self,
        time_s: Any,
        v_cmd_mps: Any,
        omega_cmd_radps: Any,
        *,
        ground: str | Sequence[str] | np.ndarray,
        slope_rad: Any = 0.0,
        pose_xyh: Any = None,
        seed: int | None = None,
    ) -> TruthRun:
        """Simulate commands on the spot; the log with the noise-free truth behind it.

        Parameters
        ----------
        time_s : array_like, shape (N,)
            Uniformly spaced, strictly increasing times (s), N >= 2.
        v_cmd_mps, omega_cmd_radps : array_like, shape (N,)
            Commanded speed (m/s) and yaw rate (rad/s).
        ground : str or sequence of str
            One ground name for the whole run or one per sample.
        slope_rad : float or array_like, shape (N,)
            Pitch along the heading (positive uphill), in (-pi/2, pi/2).
        pose_xyh : array_like, shape (N, 3), optional
            Pose to store in the log.
        seed : int, optional
            Overrides the simulator's seed for this call.

        Returns
        -------
        TruthRun

        Raises
        ------
        InvalidParameterError
            Lengths that differ from ``time_s``, bad slopes or pose, fewer than 2 samples.
        DataError
            NaN/inf commands, times not uniformly spaced or not increasing.
        UnknownNameError
            A ground name that is not one of the simulator's grounds.
        """
        t = command_series("time_s", time_s, None)
        if t.size < 2:
            raise InvalidParameterError(f"time_s must hold at least 2 samples, got {t.size}")
        uniform_step_s("time_s", t)
        n = t.size
        v = command_series("v_cmd_mps", v_cmd_mps, n)
        w = command_series("omega_cmd_radps", omega_cmd_radps, n)
        gidx = self._ground_index(ground, n)
        try:
            slope = np.asarray(slope_rad, dtype=np.float64)
        except (TypeError, ValueError):
            slope = None
        if slope is None or slope.ndim > 1 or slope.size not in (1, n):
            raise InvalidParameterError(f"slope_rad must be a number or have {n} samples, got {slope_rad!r:.80}")
        slope = np.broadcast_to(slope, (n,)).astype(np.float64)
        if not np.all(np.isfinite(slope)) or np.any(np.abs(slope) >= np.pi / 2):
            raise InvalidParameterError("slope_rad must be finite and within (-pi/2, pi/2)")
        pose = None
        if pose_xyh is not None:
            try:
                pose = np.array(pose_xyh, dtype=np.float64)
            except (TypeError, ValueError):
                raise InvalidParameterError(f"pose_xyh must be a numeric ({n}, 3) array, got {pose_xyh!r:.80}") from None
            if pose.shape != (n, 3):
                raise InvalidParameterError(f"pose_xyh must have shape ({n}, 3), got {pose.shape!r}")
        return self._simulate(t, v, w, gidx, slope, np.cos(slope), pose, self._seed(seed), "commands")

    def simulate_commands(self, time_s: Any, v_cmd_mps: Any, omega_cmd_radps: Any, *,
                          ground: str | Sequence[str] | np.ndarray, slope_rad: Any = 0.0,
                          pose_xyh: Any = None, seed: int | None = None) -> InteractionLog:
        """The :class:`InteractionLog` of :meth:`run_commands` (same parameters and errors).

        Examples
        --------
        >>> from energy import excitation_commands, robot_preset
        >>> sim = TruthSimulator(robot_preset("husky"), PAPER_GROUNDS)
        >>> p = excitation_commands(20.0, seed=1)
        >>> log = sim.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="snow_over_concrete", seed=7)
        >>> round(log.duration_s, 2), bool(log.current_left_a.min() >= 0)
        (19.99, True)
        """
        return self.run_commands(time_s, v_cmd_mps, omega_cmd_radps, ground=ground, slope_rad=slope_rad,
                                 pose_xyh=pose_xyh, seed=seed).log

    def run_drive(
        self,
        terrain: TerrainMap,
        route: Any,
        *,
        speed_mps: float = 0.5,
        accel_mps2: float = 0.5,
        turn_rate_radps: float | None = None,
        yaw_accel_radps2: float = 1.0,
        start_heading_rad: float | None = None,
        allow_obstacles: bool = False,
        seed: int | None = None,
    ) -> TruthRun:
        """Drive a route over a map; the log with the noise-free truth behind it.

        The route is either waypoints, turned into stop-turn-go commands by
        :func:`~energy.excitation.waypoint_commands` at ``current_rate_hz``, or a
        :class:`~energy.excitation.CommandProfile` with a pose (e.g. from
        :meth:`CommandProfile.from_poses`). The pose is the reference the robot follows
        (path-tracking errors are not modelled; the velocity lag shapes the currents). At
        every pose the ground is the map's class of the cell (named by
        ``terrain.ground_names``); the pitch is ``arctan(grad_x cos h + grad_y sin h)`` and
        the tilt of the vertical ``arctan(|grad|)`` from the bilinearly interpolated
        gradients.

        Parameters
        ----------
        terrain : TerrainMap
        route : array_like (K, 2) or CommandProfile
            Waypoints (m) or a command profile with ``pose_xyh``.
        speed_mps, accel_mps2, yaw_accel_radps2, start_heading_rad
            Velocity profile of waypoint routes (see :func:`waypoint_commands`).
        turn_rate_radps : float, optional
            Pivot yaw rate; ``None`` = ``robot.turn_rate_radps``.
        allow_obstacles : bool
            Drive through obstacle cells instead of raising.
        seed : int, optional
            Overrides the simulator's seed for this call (use a new one per leg).

        Returns
        -------
        TruthRun
            Its log has ``pose_xyh`` and per-sample ``ground`` labels.

        Raises
        ------
        InvalidParameterError
            A bad route or profile parameters, a profile without a pose.
        OutOfBoundsError
            The route leaves the map.
        UnknownNameError
            The route crosses unknown ground (class -1) or a class whose name is not one
            of the simulator's grounds.
        BlockedPositionError
            The route crosses an obstacle cell (unless ``allow_obstacles``).
        """
        if not isinstance(terrain, TerrainMap):
            raise InvalidParameterError(f"terrain must be a TerrainMap, got {type(terrain).__name__!r}")
        if isinstance(route, CommandProfile):
            if route.pose_xyh is None:
                raise InvalidParameterError(
                    "route is a CommandProfile without pose_xyh; drive() needs the poses to look up the map "
                    "(build it with CommandProfile.from_poses or waypoint_commands)"
                )
            profile = route
        else:
            rate = self.robot.turn_rate_radps if turn_rate_radps is None else turn_rate_radps
            profile = waypoint_commands(route, speed_mps, accel_mps2=accel_mps2, turn_rate_radps=rate,
                                        yaw_accel_radps2=yaw_accel_radps2, dt_s=1.0 / self.current_rate_hz,
                                        start_heading_rad=start_heading_rad)
        pose = np.asarray(profile.pose_xyh)
        x, y, h = pose[:, 0], pose[:, 1], pose[:, 2]
        rows, cols = terrain.rowcol(x, y)  # OutOfBoundsError off the map
        if not allow_obstacles:
            blocked = terrain.obstacle[rows, cols]
            if blocked.any():
                i = int(np.argmax(blocked))
                raise BlockedPositionError(
                    f"the route crosses an obstacle cell at ({x[i]!r}, {y[i]!r}) m (sample {i}); "
                    "pass allow_obstacles=True to drive through it"
                )
        gidx = self._map_ground_index(terrain, rows, cols, x, y)
        gx = np.asarray(terrain.sample("grad_x", x, y, method="bilinear"), dtype=np.float64)
        gy = np.asarray(terrain.sample("grad_y", x, y, method="bilinear"), dtype=np.float64)
        slope = np.arctan(gx * np.cos(h) + gy * np.sin(h))
        cos_tilt = 1.0 / np.sqrt(1.0 + gx * gx + gy * gy)
        return self._simulate(np.asarray(profile.time_s), np.asarray(profile.v_mps), np.asarray(profile.omega_radps),
                              gidx, slope, cos_tilt, pose, self._seed(seed), "drive")

    def drive(self, terrain: TerrainMap, route: Any, *, speed_mps: float = 0.5, accel_mps2: float = 0.5,
              turn_rate_radps: float | None = None, yaw_accel_radps2: float = 1.0,
              start_heading_rad: float | None = None, allow_obstacles: bool = False,
              seed: int | None = None) -> InteractionLog:
        """The :class:`InteractionLog` of :meth:`run_drive` (same parameters and errors)."""
        return self.run_drive(terrain, route, speed_mps=speed_mps, accel_mps2=accel_mps2,
                              turn_rate_radps=turn_rate_radps, yaw_accel_radps2=yaw_accel_radps2,
                              start_heading_rad=start_heading_rad, allow_obstacles=allow_obstacles,
                              seed=seed).log

    # --------------------------------------------------------------- helpers
    def _seed(self, seed: int | None) -> int:
        return self.seed if seed is None else _check_seed(seed)

    def _ground_index(self, ground: Any, n: int) -> np.ndarray:
        lookup = {name: k for k, name in enumerate(self._names)}
        if isinstance(ground, str):
            if ground not in lookup:
                raise UnknownNameError(f"ground {ground!r} is unknown; expected one of {list(self._names)!r}")
            return np.full(n, lookup[ground], dtype=np.intp)
        labels = np.asarray(ground)
        if labels.ndim != 1 or labels.size != n:
            raise InvalidParameterError(
                f"ground must be one name or one name per sample ({n}), got shape {labels.shape!r}"
            )
        if labels.dtype.kind not in "UO":
            raise InvalidParameterError(f"ground must hold str names, got dtype {labels.dtype!s}")
        uniq, inverse = np.unique(labels.astype(str), return_inverse=True)
        unknown = [u for u in uniq.tolist() if u not in lookup]
        if unknown:
            raise UnknownNameError(f"ground name(s) {unknown!r} are unknown; expected names from {list(self._names)!r}")
        return np.array([lookup[u] for u in uniq.tolist()], dtype=np.intp)[inverse.reshape(-1)]

    def _map_ground_index(self, terrain: TerrainMap, rows: np.ndarray, cols: np.ndarray,
                          x: np.ndarray, y: np.ndarray) -> np.ndarray:
        classes = np.asarray(terrain.ground[rows, cols], dtype=np.int64)
        names = terrain.ground_names
        lookup = {name: k for k, name in enumerate(self._names)}
        uniq, inverse = np.unique(classes, return_inverse=True)
        table = np.empty(uniq.size, dtype=np.intp)
        for j, cls in enumerate(uniq.tolist()):
            i = int(np.argmax(classes == cls))
            if cls == UNKNOWN_GROUND:
                raise UnknownNameError(
                    f"the route crosses unknown ground (class {UNKNOWN_GROUND}) at ({x[i]!r}, {y[i]!r}) m; "
                    "the truth simulator needs the ground of every cell it drives on"
                )
            name = names[cls]
            if name not in lookup:
                raise UnknownNameError(
                    f"the route crosses ground {name!r} (class {cls}) at ({x[i]!r}, {y[i]!r}) m, which is not one of "
                    f"the simulator's grounds {list(self._names)!r}"
                )
            table[j] = lookup[name]
        return table[inverse.reshape(-1)]

    def _track(self, cmd: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """First-order tracking (steady at the first command) and its backward derivative."""
        tau = self.velocity_time_constant_s
        if tau > 0:
            a = math.exp(-dt / tau)
            zi = signal.lfiltic([1.0 - a], [1.0, -a], y=[cmd[0]], x=[cmd[0]])
            out, _ = signal.lfilter([1.0 - a], [1.0, -a], cmd, zi=zi)
        else:
            out = cmd.copy()
        rate = np.diff(out, prepend=out[0]) / dt
        return out, rate

    def _variation_factor(self, gidx: np.ndarray, travel_m: np.ndarray, ss: np.random.SeedSequence) -> np.ndarray:
        """Resistance factor per sample (1 for grounds without variation)."""
        factor = np.ones(gidx.size)
        children = ss.spawn(len(self._names))
        for k, name in enumerate(self._names):
            var = self.variation.get(name)
            mask = gidx == k
            if var is None or var.relative_std == 0 or not mask.any():
                continue
            sigma_cells = 8.0  # grid step = length scale / 8
            step = var.length_scale_m / sigma_cells
            n_grid = int(travel_m[-1] / step) + 2
            pad = int(4 * sigma_cells) + 1  # the filter's reach (truncate=4)
            white = np.random.default_rng(children[k]).standard_normal(n_grid + 2 * pad)
            smooth = ndimage.gaussian_filter1d(white, sigma_cells)[pad : pad + n_grid]
            # unit variance: a normalised Gaussian kernel keeps 1 / (2 sqrt(pi) sigma) of it
            smooth /= math.sqrt(1.0 / (2.0 * math.sqrt(math.pi) * sigma_cells))
            z = np.interp(travel_m[mask], np.arange(n_grid) * step, smooth)
            factor[mask] = np.exp(var.relative_std * z - var.relative_std**2 / 2.0)
        return factor

    def _ground_table(self, gidx: np.ndarray, factor: np.ndarray) -> tuple[list[GroundParams], np.ndarray, np.ndarray]:
        """Ground list and per-sample index with quantised resistance factors."""
        if not self.variation:
            return [self.grounds[n] for n in self._names], gidx, factor
        level = np.round(np.log(factor) / _FACTOR_LOG_STEP).astype(np.int64)
        pairs, inverse = np.unique(np.column_stack([gidx, level]), axis=0, return_inverse=True)
        table = []
        for g, lv in pairs.tolist():
            base = self.grounds[self._names[g]]
            f = math.exp(lv * _FACTOR_LOG_STEP)
            if lv == 0:
                table.append(base)
                continue
            table.append(base.replace(
                rolling_resistance_coef=base.rolling_resistance_coef * f,
                viscous_friction_coef_s_per_m=base.viscous_friction_coef_s_per_m * f,
                lateral_friction_coef=base.effective_lateral_friction_coef * f,
            ))
        quantised = np.exp(level * _FACTOR_LOG_STEP)
        return table, inverse.reshape(-1).astype(np.intp), quantised

    def _measure_currents(self, drive_a: np.ndarray, rngs: dict[str, np.random.Generator]) -> tuple[np.ndarray, np.ndarray]:
        nm = self.noise
        n = drive_a.shape[0]
        gain = np.exp(nm.side_gain_std * rngs["side_gain"].standard_normal(2)) if nm.side_gain_std > 0 else np.ones(2)
        clean = gain * (drive_a + nm.idle_current_a)
        meas = clean.copy()
        if nm.current_noise_std_a > 0:
            meas += nm.current_noise_std_a * rngs["current_noise"].standard_normal((n, 2))
        if nm.outlier_rate > 0 and nm.outlier_magnitude_a > 0:
            r = rngs["outliers"]
            hit = r.random((n, 2)) < nm.outlier_rate
            meas += np.where(hit, nm.outlier_magnitude_a * r.uniform(0.5, 1.5, (n, 2)), 0.0)
        if nm.clip_negative:
            clean = np.maximum(clean, 0.0)
            meas = np.maximum(meas, 0.0)
        if nm.quantisation_step_a > 0:
            meas = np.round(meas / nm.quantisation_step_a) * nm.quantisation_step_a
        return clean, meas

    def _vibration(self, ta: np.ndarray, speed: np.ndarray, gidx_a: np.ndarray, factor_a: np.ndarray,
                   ss: np.random.SeedSequence) -> np.ndarray:
        m = ta.size
        dt = 1.0 / self.accel_rate_hz
        nyquist = self.accel_rate_hz / 2.0
        out = np.zeros(m)
        children = ss.spawn(len(self._names))
        for k, name in enumerate(self._names):
            mask = gidx_a == k
            if not mask.any():
                continue
            sig = self.vibration[name]
            rng = np.random.default_rng(children[k])
            scale = sig.amplitude_scale(speed) * mask
            for f0, amp, shift in zip(sig.peak_frequencies_hz, sig.peak_amplitudes_mps2, sig.peak_shifts_hz_per_mps):
                freq = f0 + shift * speed
                over = mask & (freq >= nyquist)
                if over.any():
                    raise InvalidParameterError(
                        f"vibration[{name!r}]: the peak at {f0!r} Hz + {shift!r} Hz per m/s reaches "
                        f"{float(freq[over].max())!r} Hz at the wheel speeds of this run, above the IMU's Nyquist "
                        f"frequency {nyquist!r} Hz"
                    )
                phase = 2.0 * np.pi * np.cumsum(freq) * dt + rng.uniform(0.0, 2.0 * np.pi)
                if sig.peak_width_hz > 0:
                    phase += np.cumsum(math.sqrt(2.0 * np.pi * sig.peak_width_hz * dt) * rng.standard_normal(m))
                out += amp * scale * np.cos(phase)
            if sig.roughness_mps2 > 0:
                white = rng.standard_normal(m)
                if sig.roughness_corner_hz is not None:
                    a = math.exp(-2.0 * np.pi * sig.roughness_corner_hz * dt)
                    b = math.sqrt(1.0 - a * a)
                    zi = signal.lfiltic([b], [1.0, -a], y=[white[0]])
                    white, _ = signal.lfilter([b], [1.0, -a], white, zi=zi)
                coupling = self.variation[name].vibration_coupling if name in self.variation else 0.0
                out += sig.roughness_mps2 * scale * factor_a**coupling * white
        return out

    def _simulate(self, t: np.ndarray, v_cmd: np.ndarray, w_cmd: np.ndarray, gidx: np.ndarray,
                  slope: np.ndarray, cos_tilt: np.ndarray, pose: np.ndarray | None, seed: int,
                  kind: str) -> TruthRun:
        n = t.size
        dt = float((t[-1] - t[0]) / (n - 1))
        ss = np.random.SeedSequence(seed)
        streams = dict(zip(_STREAMS, ss.spawn(len(_STREAMS))))
        rngs = {k: np.random.default_rng(s) for k, s in streams.items()}

        v, acc = self._track(v_cmd, dt)
        w, alpha = self._track(w_cmd, dt)
        half_track = self.robot.track_width_multiplier * self.robot.track_width_m / 2.0
        wheel_speed = np.maximum(np.abs(v), np.abs(w) * half_track)
        travel = np.concatenate(([0.0], np.cumsum(0.5 * (wheel_speed[1:] + wheel_speed[:-1]) * np.diff(t))))

        factor = self._variation_factor(gidx, travel, streams["variation"])
        table, tidx, factor = self._ground_table(gidx, factor)
        res = self.model.power(v, w, table, accel_mps2=acc, alpha_radps2=alpha, slope_rad=slope,
                               time_s=t, ground_index=tidx)
        current = np.asarray(res.motor_current_a)
        omega_m = np.asarray(res.motor_speed_radps)
        motoring = np.where(omega_m != 0, current * np.sign(omega_m), np.abs(current))
        clean, measured = self._measure_currents(motoring, rngs)

        m = int(math.floor((t[-1] - t[0]) * self.accel_rate_hz + 1e-9)) + 1
        ta = t[0] + np.arange(m, dtype=np.float64) / self.accel_rate_hz
        speed_a = np.interp(ta, t, wheel_speed)
        held = np.clip(np.searchsorted(t, ta + 1e-9, side="right") - 1, 0, n - 1)
        accel_z = GRAVITY_MPS2 * np.interp(ta, t, cos_tilt)
        accel_z = accel_z + self._vibration(ta, speed_a, gidx[held], np.interp(ta, t, factor), streams["vibration"])
        if self.noise.accel_noise_std_mps2 > 0:
            accel_z = accel_z + self.noise.accel_noise_std_mps2 * rngs["accel_noise"].standard_normal(m)

        labels = np.asarray(self._names)[gidx]
        used = list(dict.fromkeys(labels.tolist()))
        withheld = [e for e in EFFECTS if e not in self.model.effects]
        notes = [f"truth simulator ({kind}), seed {seed}, velocity lag {self.velocity_time_constant_s:g} s"]
        if withheld:
            notes.append(f"effects off: {', '.join(withheld)}")
        if self.variation:
            notes.append("ground variation: " + ", ".join(
                f"{g} {self.variation[g].relative_std:g}" for g in used if g in self.variation))
        for flag, what in ((res.saturated, "saturated"), (res.traction_exceeded, "beyond traction")):
            count = int(np.count_nonzero(flag))
            if count:
                notes.append(f"{count} sample(s) {what}")
                _LOG.info("truth simulator: %d of %d samples %s", count, n, what)
        meta = LogMeta(robot=self.robot.name, source="synthetic", ground_label=used[0] if len(used) == 1 else None,
                       velocity_source="commanded", notes="; ".join(notes))
        log = InteractionLog(t, v_cmd, w_cmd, measured[:, 0], measured[:, 1], ta, accel_z,
                             pose_xyh=pose, ground=labels, meta=meta)
        return TruthRun(log=log, breakdown=res, actual_v_mps=v, actual_omega_radps=w, accel_mps2=acc,
                        alpha_radps2=alpha, slope_rad=slope, resistance_factor=factor, clean_current_a=clean)


