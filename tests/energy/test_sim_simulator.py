"""Tests of energy.sim.simulator: the truth simulator's currents, noise, vibration, map driving, errors."""

from __future__ import annotations

import numpy as np
import pytest

from energy import (
    EFFECTS,
    CommandProfile,
    NoiseModel,
    PhysicsEnergyModel,
    TruthSimulator,
    ground_preset,
    robot_preset,
)
from energy.sim import PAPER_GROUNDS, VIBRATION_PRESETS, GroundVariation, VibrationSignature, vibration_preset
from terrain import (
    BlockedPositionError,
    DataError,
    InvalidParameterError,
    OutOfBoundsError,
    TerrainMap,
    UnknownNameError,
    ramp_map,
)

G = 9.80665
HUSKY = robot_preset("husky")
WOOD = PAPER_GROUNDS["coated_wood"]
WOOD_ONLY = {"coated_wood": WOOD}
DT = 0.01


def steady(n: int = 4000, v: float = 0.4, omega: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return np.arange(n) * DT, np.full(n, v), np.full(n, omega)


def quiet(**kw: object) -> NoiseModel:
    base = dict(current_noise_std_a=0.0, outlier_rate=0.0, quantisation_step_a=0.0, accel_noise_std_mps2=0.0)
    base.update(kw)
    return NoiseModel(**base)  # type: ignore[arg-type]


def only_peak(freq: float, amp: float = 0.5, **kw: object) -> dict[str, VibrationSignature]:
    sig = VibrationSignature(peak_frequencies_hz=(freq,), peak_amplitudes_mps2=(amp,), peak_width_hz=0.0, **kw)
    return {"coated_wood": sig}


def amplitude_spectrum(x: np.ndarray, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    x = x - x.mean()
    return np.fft.rfftfreq(x.size, 1.0 / rate_hz), np.abs(np.fft.rfft(x)) * 2.0 / x.size


# ------------------------------------------------------------------ determinism, streams
def test_same_seed_same_log_other_seed_other_log() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, variation={"coated_wood": GroundVariation(relative_std=0.1)})
    t, v, w = steady(2000, 0.3, 0.5)
    a = sim.simulate_commands(t, v, w, ground="coated_wood", seed=5)
    b = sim.simulate_commands(t, v, w, ground="coated_wood", seed=5)
    c = sim.simulate_commands(t, v, w, ground="coated_wood", seed=6)
    for name in ("current_left_a", "current_right_a", "accel_z_mps2", "accel_time_s"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert not np.array_equal(a.current_left_a, c.current_left_a)
    assert not np.array_equal(a.accel_z_mps2, c.accel_z_mps2)
    # the simulator's own seed is the default of every call
    d = TruthSimulator(HUSKY, PAPER_GROUNDS, variation={"coated_wood": GroundVariation(relative_std=0.1)},
                       seed=5).simulate_commands(t, v, w, ground="coated_wood")
    assert np.array_equal(a.current_right_a, d.current_right_a)


def test_switching_one_component_leaves_the_other_draws_alone() -> None:
    t, v, w = steady(3000)
    base = dict(current_noise_std_a=0.2, quantisation_step_a=0.0, accel_noise_std_mps2=0.05)
    a = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel(outlier_rate=0.0, **base))
    b = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel(outlier_rate=0.05, **base))
    la = a.simulate_commands(t, v, w, ground="coated_wood", seed=1)
    lb = b.simulate_commands(t, v, w, ground="coated_wood", seed=1)
    assert np.array_equal(la.accel_z_mps2, lb.accel_z_mps2)
    same = la.current_left_a == lb.current_left_a
    assert 0.9 < same.mean() < 1.0  # only the outlier samples differ


# ------------------------------------------------------------------ currents vs physics
def motoring(model: PhysicsEnergyModel, run, ground=WOOD) -> np.ndarray:  # type: ignore[no-untyped-def]
    res = model.power(run.actual_v_mps, run.actual_omega_radps, ground, accel_mps2=run.accel_mps2,
                      alpha_radps2=run.alpha_radps2, slope_rad=run.slope_rad)
    i, wm = res.motor_current_a, res.motor_speed_radps
    return np.where(wm != 0, i * np.sign(wm), np.abs(i))


def test_noiseless_currents_are_the_physics_motoring_currents() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel.off())
    p = CommandProfile(np.arange(3000) * DT, np.r_[np.zeros(500), np.full(1000, 0.4), np.full(1500, 0.2)],
                       np.r_[np.zeros(1000), np.full(1000, 0.7), np.full(1000, -0.3)])
    run = sim.run_commands(p.time_s, p.v_mps, p.omega_radps, ground="coated_wood", slope_rad=0.05)
    expected = motoring(PhysicsEnergyModel(HUSKY), run)
    logged = np.column_stack([run.log.current_left_a, run.log.current_right_a])
    np.testing.assert_allclose(logged, expected, rtol=1e-12, atol=1e-12)
    assert logged.min() < 0  # braking shows as negative without clipping
    # idle offset and clipping like the Husky driver
    sim2 = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=quiet(current_offset_a=0.59, clip_negative=True))
    log2 = sim2.simulate_commands(p.time_s, p.v_mps, p.omega_radps, ground="coated_wood", slope_rad=0.05)
    np.testing.assert_allclose(log2.current_left_a, np.maximum(expected[:, 0] + 0.59, 0.0), atol=1e-12)
    np.testing.assert_allclose(log2.current_right_a, np.maximum(expected[:, 1] + 0.59, 0.0), atol=1e-12)


def test_pivot_draws_on_both_sides_and_a_braked_inner_side_reads_zero() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=quiet(current_offset_a=0.0))
    t, v, w = steady(1000, 0.0, 1.0)
    pivot = sim.simulate_commands(t, v, w, ground="coated_wood")
    assert pivot.current_left_a[-1] > 1.0 and pivot.current_right_a[-1] > 1.0
    assert pivot.current_left_a[-1] == pytest.approx(pivot.current_right_a[-1], rel=1e-6)
    t, v, w = steady(1000, 0.4, 0.35)  # gentle left arc: inner (left) side back-driven
    arc = sim.simulate_commands(t, v, w, ground="coated_wood")
    assert arc.current_left_a[-1] == 0.0 and arc.current_right_a[-1] > 1.0


def test_velocity_lag_is_first_order() -> None:
    tau = 0.2
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel.off(), velocity_time_constant_s=tau)
    n = 300
    v = np.r_[np.zeros(100), np.full(n - 100, 0.4)]
    run = sim.run_commands(np.arange(n) * DT, v, np.zeros(n), ground="coated_wood")
    k = 100 + int(round(tau / DT))  # one time constant after the step
    assert run.actual_v_mps[99] == 0.0
    assert run.actual_v_mps[k] == pytest.approx(0.4 * (1 - np.exp(-(tau + DT) / tau)), rel=1e-9)
    assert run.log.v_mps[k] == 0.4  # the log keeps the commands
    np.testing.assert_allclose(np.cumsum(run.accel_mps2) * DT, run.actual_v_mps, atol=1e-12)


def test_withheld_effect_changes_the_current_by_its_closed_form() -> None:
    beta = 0.1
    mo = HUSKY.motor
    expected = HUSKY.mass_kg / 2 * G * np.sin(beta) * HUSKY.wheel_radius_m / (
        mo.gear_ratio * mo.gear_efficiency * mo.torque_constant_nm_per_a)
    t, v, w = steady(500, 0.4)
    kw = dict(noise=NoiseModel.off(), velocity_time_constant_s=0.0)
    few = ("coulomb_friction", "gear_losses")
    on = TruthSimulator(HUSKY, PAPER_GROUNDS, effects=few + ("slope",), **kw)
    off = TruthSimulator(HUSKY, PAPER_GROUNDS, effects=few, **kw)
    d_on = on.simulate_commands(t, v, w, ground="coated_wood", slope_rad=beta)
    d_off = off.simulate_commands(t, v, w, ground="coated_wood", slope_rad=beta)
    np.testing.assert_allclose(d_on.current_left_a - d_off.current_left_a, expected, rtol=1e-12)
    np.testing.assert_allclose(d_on.current_right_a - d_off.current_right_a, expected, rtol=1e-12)
    assert "effects off" in d_off.meta.notes and "slope" in d_off.meta.notes
    # with every other effect on, the slope term still accounts for the difference
    full = TruthSimulator(HUSKY, PAPER_GROUNDS, **kw)
    held = TruthSimulator(HUSKY, PAPER_GROUNDS, effects=[e for e in EFFECTS if e != "slope"], **kw)
    diff = (full.simulate_commands(t, v, w, ground="coated_wood", slope_rad=beta).current_left_a
            - held.simulate_commands(t, v, w, ground="coated_wood", slope_rad=beta).current_left_a)
    assert diff[-1] == pytest.approx(expected, rel=1e-2)


# ------------------------------------------------------------------ measurement model
def test_quantisation_step_is_visible() -> None:
    step = 0.13
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel(quantisation_step_a=step))
    t, v, w = steady(2000, 0.3, 0.7)
    log = sim.simulate_commands(t, v, w, ground="coated_wood", seed=2)
    for cur in (log.current_left_a, log.current_right_a):
        k = cur / step
        np.testing.assert_allclose(k, np.round(k), atol=1e-9)
        levels = np.unique(np.round(k))
        assert levels.size > 3  # noise spreads the readings over several steps
        assert np.min(np.diff(levels)) == 1.0


def test_noise_std_matches_configuration() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=quiet(current_noise_std_a=0.3, current_offset_a=3.0))
    t, v, w = steady(20000, 0.4)
    run = sim.run_commands(t, v, w, ground="coated_wood", seed=3)
    resid = np.column_stack([run.log.current_left_a, run.log.current_right_a]) - run.clean_current_a
    assert resid.std() == pytest.approx(0.3, rel=0.03)
    assert abs(resid.mean()) < 0.01


def test_outlier_rate_and_magnitude() -> None:
    rate, mag = 0.01, 2.0
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=quiet(outlier_rate=rate, outlier_magnitude_a=mag))
    t, v, w = steady(20000, 0.4)
    run = sim.run_commands(t, v, w, ground="coated_wood", seed=4)
    spikes = np.column_stack([run.log.current_left_a, run.log.current_right_a]) - run.clean_current_a
    hit = spikes != 0
    sigma = np.sqrt(rate * (1 - rate) / hit.size)
    assert abs(hit.mean() - rate) < 4 * sigma
    assert spikes[hit].min() >= 0.5 * mag - 1e-12 and spikes[hit].max() <= 1.5 * mag + 1e-12


def test_side_gain_spreads_runs() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=quiet(side_gain_std=0.1, current_offset_a=1.0))
    t, v, w = steady(200, 0.4)
    ratios = [sim.run_commands(t, v, w, ground="coated_wood", seed=s).clean_current_a[-1] for s in range(20)]
    r = np.array(ratios)
    assert np.std(r[:, 0] / r[:, 1]) > 0.03
    assert np.isclose(r[:, 0] / r[:, 1], 1.0).sum() == 0


# ------------------------------------------------------------------ vibration
def test_gravity_and_sensor_noise_at_rest() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=quiet(accel_noise_std_mps2=0.05))
    t, v, w = steady(5000, 0.0)
    log = sim.simulate_commands(t, v, w, ground="coated_wood", slope_rad=0.2)
    assert log.accel_z_mps2.mean() == pytest.approx(G * np.cos(0.2), abs=0.005)
    assert log.accel_z_mps2.std() == pytest.approx(0.05, rel=0.05)


def test_spectrum_peak_at_the_configured_frequency() -> None:
    sim = TruthSimulator(HUSKY, WOOD_ONLY, vibration=only_peak(17.0), noise=NoiseModel.off(),
                         accel_rate_hz=200.0)
    t, v, w = steady(4000, 0.4)
    log = sim.simulate_commands(t, v, w, ground="coated_wood")
    assert log.accel_rate_hz == pytest.approx(200.0)
    f, amp = amplitude_spectrum(log.accel_z_mps2, 200.0)
    assert f[np.argmax(amp)] == pytest.approx(17.0, abs=0.05)
    assert amp.max() == pytest.approx(0.5, rel=0.1)  # amplitude at the reference speed
    # a speed-proportional line (joints every 0.25 m: 4 Hz per m/s) on top of 2 Hz
    sim2 = TruthSimulator(HUSKY, WOOD_ONLY, noise=NoiseModel.off(),
                          vibration=only_peak(2.0, peak_shifts_hz_per_mps=(4.0,)))
    log2 = sim2.simulate_commands(t, np.full(t.size, 0.5), w, ground="coated_wood")
    f2, amp2 = amplitude_spectrum(log2.accel_z_mps2, 100.0)
    assert f2[np.argmax(amp2)] == pytest.approx(4.0, abs=0.05)


def test_amplitude_grows_with_speed() -> None:
    sig = VibrationSignature(peak_frequencies_hz=(8.0, 20.0), peak_amplitudes_mps2=(0.3, 0.2), roughness_mps2=0.2,
                             speed_exponent=1.5)
    sim = TruthSimulator(HUSKY, WOOD_ONLY, vibration={"coated_wood": sig}, noise=NoiseModel.off())
    rms = []
    for speed in (0.1, 0.2, 0.4):
        t, v, w = steady(6000, speed)
        rms.append(sim.simulate_commands(t, v, w, ground="coated_wood", seed=1).accel_z_mps2.std())
        assert rms[-1] == pytest.approx(sig.rms_mps2(speed), rel=0.1)
    assert rms[0] < rms[1] < rms[2]
    assert rms[2] / rms[1] == pytest.approx(2**1.5, rel=0.1)
    # at rest the ground adds nothing
    t, v, w = steady(1000, 0.0)
    assert np.ptp(sim.simulate_commands(t, v, w, ground="coated_wood").accel_z_mps2) == 0.0


def test_turning_in_place_shakes_too() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel.off())
    t, v, w = steady(3000, 0.0, 1.0)
    log = sim.simulate_commands(t, v, w, ground="coated_wood")
    wheel_speed = HUSKY.track_width_multiplier * HUSKY.track_width_m / 2 * 1.0
    assert log.accel_z_mps2[500:].std() == pytest.approx(VIBRATION_PRESETS["coated_wood"].rms_mps2(wheel_speed), rel=0.15)


def test_grounds_have_different_spectra() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel.off())
    t, v, w = steady(6000, 0.4)
    peaks, rms = {}, {}
    for name in PAPER_GROUNDS:
        log = sim.simulate_commands(t, v, w, ground=name, seed=1)
        f, amp = amplitude_spectrum(log.accel_z_mps2, 100.0)
        smooth = np.convolve(amp, np.ones(21) / 21, mode="same")
        peaks[name] = f[np.argmax(smooth)]
        rms[name] = log.accel_z_mps2.std()
        expected = vibration_preset(name).peak_frequencies_at(0.4)
        strongest = expected[int(np.argmax(vibration_preset(name).peak_amplitudes_mps2))]
        assert peaks[name] == pytest.approx(strongest, abs=0.5)
    assert len({round(p) for p in peaks.values()}) == 3
    assert rms["coated_wood"] < 0.5 * min(rms["snow_over_stone_tiles"], rms["snow_over_concrete"])


def test_per_sample_grounds() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel.off())
    t, v, w = steady(2000, 0.4, 0.5)
    labels = np.where(np.arange(2000) < 1000, "coated_wood", "snow_over_concrete")
    log = sim.simulate_commands(t, v, w, ground=labels)
    assert log.meta.ground_label is None
    assert log.ground[0] == "coated_wood" and log.ground[-1] == "snow_over_concrete"
    assert log.current_right_a[900] != pytest.approx(log.current_right_a[1900], rel=1e-3)
    wood, snow = log.accel_z_mps2[:1000], log.accel_z_mps2[1000:]
    assert snow.std() > 2 * wood.std()


def test_ground_variation_scales_resistance() -> None:
    var = GroundVariation(relative_std=0.2, length_scale_m=1.0)
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel.off(), variation={"coated_wood": var})
    t, v, w = steady(40000, 0.5)
    run = sim.run_commands(t, v, w, ground="coated_wood", seed=8)
    f = run.resistance_factor
    assert np.log(f).std() == pytest.approx(0.2, rel=0.25)
    assert np.mean(f) == pytest.approx(1.0, abs=0.05)
    # straight driving: the current above the no-resistance part follows the factor
    plain = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel.off()).run_commands(t, v, w, ground="coated_wood")
    assert np.all(plain.resistance_factor == 1.0)
    ratio = run.log.current_left_a[100:] / plain.log.current_left_a[100:]
    assert np.corrcoef(ratio, f[100:])[0, 1] > 0.99


# ------------------------------------------------------------------ driving on a map
def test_drive_on_a_ramp_gets_the_slope_along_the_heading() -> None:
    grade = 0.1
    tmap = ramp_map((30, 30), 1.0, grade=grade, ground="asphalt")
    sim = TruthSimulator(HUSKY, {"asphalt": ground_preset("asphalt")}, noise=NoiseModel.off())
    run = sim.run_drive(tmap, [[3.0, 3.0], [25.0, 3.0], [25.0, 25.0], [3.0, 25.0]], speed_mps=0.5)
    log = run.log
    pose = log.pose_xyh
    east = (log.v_mps > 0) & (np.abs(pose[:, 2]) < 1e-9)
    north = (log.v_mps > 0) & (np.abs(pose[:, 2] - np.pi / 2) < 1e-9)
    west = (log.v_mps > 0) & (np.abs(np.abs(pose[:, 2]) - np.pi) < 1e-9)
    assert east.sum() > 100 and north.sum() > 100 and west.sum() > 100
    np.testing.assert_allclose(run.slope_rad[east], np.arctan(grade), atol=1e-9)
    np.testing.assert_allclose(run.slope_rad[north], 0.0, atol=1e-9)
    np.testing.assert_allclose(run.slope_rad[west], -np.arctan(grade), atol=1e-9)
    assert pose[-1] == pytest.approx([3.0, 25.0, np.pi])
    assert set(log.ground.tolist()) == {"asphalt"}
    assert log.drive_rate_hz == pytest.approx(100.0)
    assert log.accel_z_mps2.mean() == pytest.approx(G / np.sqrt(1 + grade**2), abs=0.005)  # tilted gravity
    # uphill costs more current than downhill at the same speed
    assert log.current_right_a[east].mean() > log.current_right_a[west].mean() + 0.5


def test_drive_follows_ground_classes_and_pose_profiles() -> None:
    ground = np.zeros((10, 20), dtype=np.int16)
    ground[:, 10:] = 1
    tmap = TerrainMap(np.zeros((10, 20)), 1.0, ground=ground, ground_names={0: "coated_wood", 1: "snow_over_concrete"})
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS, noise=NoiseModel.off(), seed=3)
    log = sim.drive(tmap, [[1.0, 5.0], [19.0, 5.0]], speed_mps=0.4)
    x = log.pose_xyh[:, 0]
    assert np.all(log.ground[x < 9.99] == "coated_wood") and np.all(log.ground[x > 10.01] == "snow_over_concrete")
    # a pose trajectory instead of waypoints
    t = np.arange(0, 10.0, 0.01)
    pose = np.column_stack([2.0 + 0.3 * t, np.full(t.size, 5.0), np.zeros(t.size)])
    log2 = sim.drive(tmap, CommandProfile.from_poses(t, pose))
    assert log2.v_mps == pytest.approx(np.full(t.size, 0.3))
    assert np.array_equal(log2.pose_xyh, pose)


def test_drive_errors() -> None:
    ground = np.zeros((10, 10), dtype=np.int16)
    ground[:, 5:] = -1
    obstacle = np.zeros((10, 10), dtype=bool)
    obstacle[8, 2] = True
    tmap = TerrainMap(np.zeros((10, 10)), 1.0, ground=ground, ground_names={0: "asphalt"}, obstacle=obstacle)
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS)
    with pytest.raises(UnknownNameError, match="'asphalt'"):
        sim.drive(tmap, [[1.0, 1.0], [3.0, 1.0]])
    sim2 = TruthSimulator(HUSKY, {"asphalt": ground_preset("asphalt")})
    with pytest.raises(UnknownNameError, match="unknown ground"):
        sim2.drive(tmap, [[1.0, 1.0], [8.0, 1.0]])
    with pytest.raises(OutOfBoundsError):
        sim2.drive(tmap, [[1.0, 1.0], [1.0, 12.0]])
    with pytest.raises(BlockedPositionError, match="obstacle"):
        sim2.drive(tmap, [[2.5, 1.0], [2.5, 9.5]])
    # allow_obstacles drives the whole route through the obstacle cell: 8.5 m rest to rest at
    # 0.5 m/s with 0.5 m/s^2 takes 8.5 / 0.5 + 0.5 / 0.5 = 18 s, sampled at current_rate_hz
    log = sim2.drive(tmap, [[2.5, 1.0], [2.5, 9.5]], allow_obstacles=True)
    assert len(log) == 1801 and log.duration_s == pytest.approx(18.0)
    assert np.diff(log.time_s) == pytest.approx(np.full(1800, 0.01))
    assert log.pose_xyh[-1] == pytest.approx([2.5, 9.5, np.pi / 2])
    rows, cols = tmap.rowcol(log.pose_xyh[:, 0], log.pose_xyh[:, 1])
    assert np.any(obstacle[rows, cols])
    cruising = log.v_mps > 0.45
    for side in (log.current_left_a, log.current_right_a):
        assert side.min() >= 0.0 and side.max() < 10.0  # motoring currents, braking clipped to 0
        assert 0.59 < side[cruising].mean() < 3.0  # more than the idle current while driving
    with pytest.raises(InvalidParameterError, match="pose_xyh"):
        sim2.drive(tmap, CommandProfile([0.0, 0.1], [0.0, 0.0], [0.0, 0.0]))
    with pytest.raises(InvalidParameterError, match="TerrainMap"):
        sim2.drive(np.zeros((3, 3)), [[1.0, 1.0], [2.0, 1.0]])


# ------------------------------------------------------------------ bad input
def test_bad_commands() -> None:
    sim = TruthSimulator(HUSKY, PAPER_GROUNDS)
    t, v, w = steady(100)
    with pytest.raises(UnknownNameError, match="'gravel'"):
        sim.simulate_commands(t, v, w, ground="gravel")
    with pytest.raises(UnknownNameError, match="'moon'"):
        sim.simulate_commands(t, v, w, ground=["coated_wood"] * 99 + ["moon"])
    with pytest.raises(InvalidParameterError, match="one name per sample"):
        sim.simulate_commands(t, v, w, ground=["coated_wood"] * 3)
    bad = v.copy()
    bad[10] = np.nan
    with pytest.raises(DataError, match="v_cmd_mps must be finite"):
        sim.simulate_commands(t, bad, w, ground="coated_wood")
    with pytest.raises(InvalidParameterError, match="omega_cmd_radps must have the length"):
        sim.simulate_commands(t, v, w[:-1], ground="coated_wood")
    with pytest.raises(DataError, match="uniformly spaced"):
        sim.simulate_commands(np.r_[t[:50], t[50:] + 0.5], v, w, ground="coated_wood")
    with pytest.raises(InvalidParameterError, match="slope_rad"):
        sim.simulate_commands(t, v, w, ground="coated_wood", slope_rad=2.0)
    with pytest.raises(InvalidParameterError, match="seed"):
        sim.simulate_commands(t, v, w, ground="coated_wood", seed=-1)


@pytest.mark.parametrize("seed", [-1, 2**32, 1.0, True, "3"])
def test_seed_follows_the_one_seed_rule(seed: object) -> None:
    t, v, w = steady(20)
    with pytest.raises(InvalidParameterError, match=r"seed must be None or an integer in \[0, 2\*\*32\)"):
        TruthSimulator(HUSKY, PAPER_GROUNDS, seed=seed)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"seed must be None or an integer in \[0, 2\*\*32\)"):
        TruthSimulator(HUSKY, PAPER_GROUNDS).simulate_commands(t, v, w, ground="coated_wood", seed=seed)


def test_string_numbers_name_the_parameter() -> None:
    with pytest.raises(InvalidParameterError, match="TruthSimulator.accel_rate_hz must be a real number, got 'fast'"):
        TruthSimulator(HUSKY, PAPER_GROUNDS, accel_rate_hz="fast")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="NoiseModel.current_offset_a must be a real number"):
        NoiseModel(current_offset_a="0.5")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="NoiseModel.clip_negative must be True or False"):
        NoiseModel(clip_negative="no")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match=r"VibrationSignature.peak_frequencies_hz\[0\] must be a real"):
        VibrationSignature(peak_frequencies_hz=("12",), peak_amplitudes_mps2=(0.1,))


def test_bad_configuration() -> None:
    with pytest.raises(UnknownNameError, match="flying"):
        TruthSimulator(HUSKY, PAPER_GROUNDS, effects=["flying"])
    custom = {"mud": ground_preset("sand").replace(name="mud")}
    with pytest.raises(UnknownNameError, match="vibration signature.*'mud'"):
        TruthSimulator(HUSKY, custom)
    with pytest.raises(InvalidParameterError, match="Nyquist"):
        TruthSimulator(HUSKY, WOOD_ONLY, vibration=only_peak(60.0))
    with pytest.raises(InvalidParameterError, match="GroundParams"):
        TruthSimulator(HUSKY, {"coated_wood": "wood"})  # type: ignore[dict-item]
    with pytest.raises(InvalidParameterError, match="noise"):
        TruthSimulator(HUSKY, PAPER_GROUNDS, noise={"std": 0.1})  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="current_noise_std_a"):
        NoiseModel(current_noise_std_a=-0.1)
    with pytest.raises(InvalidParameterError, match="outlier_rate"):
        NoiseModel(outlier_rate=1.5)
    with pytest.raises(InvalidParameterError, match="peak_amplitudes_mps2"):
        VibrationSignature(peak_frequencies_hz=(1.0, 2.0), peak_amplitudes_mps2=(0.1,))
    with pytest.raises(InvalidParameterError, match="reference_speed_mps"):
        VibrationSignature(reference_speed_mps=0.0)
    with pytest.raises(InvalidParameterError, match="relative_std"):
        GroundVariation(relative_std=-0.1)
    with pytest.raises(UnknownNameError, match="mud"):
        vibration_preset("mud")
    # a shifting line that crosses the Nyquist frequency at this run's speeds
    sim = TruthSimulator(HUSKY, WOOD_ONLY, vibration=only_peak(40.0, peak_shifts_hz_per_mps=(50.0,)))
    t, v, w = steady(100)
    with pytest.raises(InvalidParameterError, match="Nyquist"):
        sim.simulate_commands(t, v, w, ground="coated_wood")
