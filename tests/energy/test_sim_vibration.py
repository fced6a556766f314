"""energy.sim.vibration: vibration signatures and the vertical vibration they give."""

from __future__ import annotations

import math

import numpy as np
import pytest

from energy.sim import VibrationSignature, vibration_accel_mps2
from terrain import InvalidParameterError

RATE_HZ = 100.0


def test_defaults_and_normalised_tuples():
    sig = VibrationSignature(peak_frequencies_hz=[12, 30], peak_amplitudes_mps2=[0.2, 0.1])
    assert sig.peak_frequencies_hz == (12.0, 30.0) and sig.peak_shifts_hz_per_mps == (0.0, 0.0)
    assert (sig.reference_speed_mps, sig.speed_exponent, sig.roughness_corner_hz) == (0.4, 1.0, None)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"peak_frequencies_hz": 12.0}, "VibrationSignature.peak_frequencies_hz must be a sequence of numbers"),
        ({"peak_frequencies_hz": (-1.0,), "peak_amplitudes_mps2": (0.1,)}, r"peak_frequencies_hz\[0\] must be >= 0"),
        ({"peak_frequencies_hz": (1.0,), "peak_amplitudes_mps2": (0.1,), "peak_shifts_hz_per_mps": (1.0, 2.0)},
         r"peak_shifts_hz_per_mps must have one entry per peak \(1\), got 2"),
        ({"roughness_corner_hz": 0.0}, "roughness_corner_hz must be > 0"),
        ({"speed_exponent": -1.0}, "speed_exponent must be >= 0"),
    ],
)
def test_bad_signatures_are_refused(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        VibrationSignature(**kwargs)


def test_amplitude_scale_frequencies_and_rms():
    sig = VibrationSignature(peak_frequencies_hz=(0.0, 10.0), peak_amplitudes_mps2=(0.3, 0.4),
                             peak_shifts_hz_per_mps=(5.0, 0.0), roughness_mps2=0.1, speed_exponent=2.0)
    assert sig.amplitude_scale([0.0, 0.2, -0.8]).tolist() == [0.0, 0.25, 4.0]
    assert sig.peak_frequencies_at(-0.4) == (2.0, 10.0)
    assert sig.rms_mps2(0.4) == pytest.approx(math.sqrt(0.01 + 0.09 / 2 + 0.16 / 2))
    assert sig.rms_mps2(0.8) == pytest.approx(4.0 * sig.rms_mps2(0.4))
    assert sig.rms_mps2(0.0) == 0.0


def _accel(sig, speed, n=20_000, seed=0, factor=None, coupling=0.0):
    index = np.zeros(n, int)
    factor = np.ones(n) if factor is None else factor
    return vibration_accel_mps2(np.full(n, speed), index, factor, [("g", sig, coupling)], RATE_HZ,
                                np.random.SeedSequence(seed))


def test_a_pure_tone_has_its_amplitude_and_frequency():
    sig = VibrationSignature(peak_frequencies_hz=(12.5,), peak_amplitudes_mps2=(0.2,), peak_width_hz=0.0)
    a = _accel(sig, 0.4)
    assert a.std() == pytest.approx(0.2 / math.sqrt(2), rel=1e-3)
    freqs = np.fft.rfftfreq(a.size, 1.0 / RATE_HZ)
    assert freqs[np.argmax(np.abs(np.fft.rfft(a)))] == pytest.approx(12.5)


def test_roughness_scales_with_the_resistance_factor_through_the_coupling():
    sig = VibrationSignature(roughness_mps2=0.3)
    plain = _accel(sig, 0.4, seed=2)
    assert plain.std() == pytest.approx(0.3, rel=0.03)
    doubled = _accel(sig, 0.4, seed=2, factor=np.full(20_000, 2.0), coupling=1.0)
    np.testing.assert_allclose(doubled, 2.0 * plain)


def test_at_rest_and_on_other_grounds_nothing_is_added():
    sig = VibrationSignature(peak_frequencies_hz=(5.0,), peak_amplitudes_mps2=(1.0,), roughness_mps2=1.0)
    assert np.array_equal(_accel(sig, 0.0, n=100), np.zeros(100))
    out = vibration_accel_mps2(np.full(10, 0.4), np.ones(10, int), np.ones(10), [("g", sig, 0.0)], RATE_HZ,
                               np.random.SeedSequence(0))
    assert np.array_equal(out, np.zeros(10))


def test_seeded():
    sig = VibrationSignature(peak_frequencies_hz=(5.0,), peak_amplitudes_mps2=(1.0,), roughness_mps2=0.5,
                             roughness_corner_hz=10.0)
    assert np.array_equal(_accel(sig, 0.3, n=500, seed=9), _accel(sig, 0.3, n=500, seed=9))
    assert not np.array_equal(_accel(sig, 0.3, n=500, seed=9), _accel(sig, 0.3, n=500, seed=10))


def test_a_peak_at_the_nyquist_frequency_is_refused():
    sig = VibrationSignature(peak_frequencies_hz=(40.0,), peak_amplitudes_mps2=(0.1,), peak_shifts_hz_per_mps=(25.0,))
    with pytest.raises(InvalidParameterError, match=r"vibration\['g'\]: the peak at 40.0 Hz .* Nyquist frequency 50.0 Hz"):
        _accel(sig, 0.4, n=10)
