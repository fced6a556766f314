"""Ground vibration: the :class:`VibrationSignature` of a ground and the synthetic IMU's vertical acceleration."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import signal

from terrawatt_base.checks import check_real
from terrawatt_base.errors import InvalidParameterError

__all__ = ["VibrationSignature", "vibration_accel_mps2"]

_OWN = "VibrationSignature"


def _nonnegative(name: str, value: Any, *, strict: bool = False) -> float:
    return check_real(name, value, low=0.0, low_inclusive=not strict, owner=_OWN)


def _real_tuple(name: str, values: Any) -> tuple[float, ...]:
    try:
        items = tuple(values)
    except TypeError:
        raise InvalidParameterError(f"{_OWN}.{name} must be a sequence of numbers, got {values!r}") from None
    return tuple(_nonnegative(f"{name}[{k}]", v) for k, v in enumerate(items))


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
        freqs = _real_tuple("peak_frequencies_hz", self.peak_frequencies_hz)
        amps = _real_tuple("peak_amplitudes_mps2", self.peak_amplitudes_mps2)
        if len(amps) != len(freqs):
            raise InvalidParameterError(
                f"{_OWN}.peak_amplitudes_mps2 must have one entry per peak ({len(freqs)}), got {len(amps)}"
            )
        shifts = (0.0,) * len(freqs) if self.peak_shifts_hz_per_mps is None else _real_tuple(
            "peak_shifts_hz_per_mps", self.peak_shifts_hz_per_mps)
        if len(shifts) != len(freqs):
            raise InvalidParameterError(
                f"{_OWN}.peak_shifts_hz_per_mps must have one entry per peak ({len(freqs)}), got {len(shifts)}"
            )
        object.__setattr__(self, "peak_frequencies_hz", freqs)
        object.__setattr__(self, "peak_amplitudes_mps2", amps)
        object.__setattr__(self, "peak_shifts_hz_per_mps", shifts)
        _nonnegative("peak_width_hz", self.peak_width_hz)
        _nonnegative("roughness_mps2", self.roughness_mps2)
        if self.roughness_corner_hz is not None:
            _nonnegative("roughness_corner_hz", self.roughness_corner_hz, strict=True)
        _nonnegative("reference_speed_mps", self.reference_speed_mps, strict=True)
        _nonnegative("speed_exponent", self.speed_exponent)

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


def vibration_accel_mps2(
    wheel_speed_mps: np.ndarray,
    ground_index: np.ndarray,
    resistance_factor: np.ndarray,
    signatures: Sequence[tuple[str, VibrationSignature, float]],
    accel_rate_hz: float,
    seed: np.random.SeedSequence,
) -> np.ndarray:
    """The grounds' vertical vibration (m/s^2, without gravity) at the IMU's samples.

    Parameters
    ----------
    wheel_speed_mps, ground_index, resistance_factor : numpy.ndarray, shape (M,)
        Per IMU sample (uniform at ``accel_rate_hz``): the wheel speed, the index of the
        ground into ``signatures`` and the ground-variation factor.
    signatures : sequence of (name, VibrationSignature, coupling)
        One per ground: its name (for messages), its signature and the exponent of the
        resistance factor on its roughness (0 = unaffected).
    accel_rate_hz : float
        The IMU rate (Hz).
    seed : numpy.random.SeedSequence
        One child stream is spawned per ground, in order.

    Raises
    ------
    InvalidParameterError
        A speed-shifted peak reaches the IMU's Nyquist frequency.
    """
    m = wheel_speed_mps.size
    speed = wheel_speed_mps
    dt = 1.0 / accel_rate_hz
    nyquist = accel_rate_hz / 2.0
    out = np.zeros(m)
    children = seed.spawn(len(signatures))
    for k, (name, sig, coupling) in enumerate(signatures):
        mask = ground_index == k
        if not mask.any():
            continue
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
            out += sig.roughness_mps2 * scale * resistance_factor**coupling * white
    return out
