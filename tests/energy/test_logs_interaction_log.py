"""Tests of energy.logs.interaction_log: InteractionLog validation, resampling, slicing, joining, gap splits."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from log_samples import make_log

from energy import InteractionLog, LogMeta
from energy.logs import DEFAULT_GAP_FACTOR
from terrain import (
    DataError,
    DataRepairWarning,
    InvalidParameterError,
    UnknownNameError,
)


# ------------------------------------------------------------------ construction
def test_arrays_are_float_readonly_copies():
    t = np.arange(5, dtype=np.int64)
    log = make_log(time_s=t, v_mps=[0, 1, 2, 3, 4], omega_radps=np.zeros(5), current_left_a=np.ones(5),
                   current_right_a=np.ones(5), n=5)
    assert log.time_s.dtype == np.float64
    assert not log.time_s.flags.writeable and not log.accel_z_mps2.flags.writeable
    t[0] = 99
    assert log.time_s[0] == 0.0
    with pytest.raises(ValueError):
        log.v_mps[0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        log.v_mps = np.zeros(5)


def test_len_duration_rates():
    log = make_log()
    assert len(log) == 11
    assert log.duration_s == pytest.approx(1.0)
    assert log.drive_rate_hz == pytest.approx(10.0)
    assert log.accel_rate_hz == pytest.approx(100.0)
    assert "testbot" in repr(log) and "11 samples" in repr(log)


def test_rates_need_two_samples():
    log = make_log(n=1, m=1)
    with pytest.raises(DataError, match="at least 2 drive samples"):
        _ = log.drive_rate_hz
    with pytest.raises(DataError, match="at least 2 acceleration samples"):
        _ = log.accel_rate_hz


@pytest.mark.parametrize("field", ["v_mps", "omega_radps", "current_left_a", "current_right_a"])
def test_length_mismatch(field):
    with pytest.raises(InvalidParameterError, match=f"{field} must have the length of time_s"):
        make_log(**{field: np.zeros(3)})


def test_accel_length_mismatch_and_2d():
    with pytest.raises(InvalidParameterError, match="accel_z_mps2 must have the length"):
        make_log(accel_z_mps2=np.zeros(3))
    with pytest.raises(InvalidParameterError, match="must be a 1-D array"):
        make_log(v_mps=np.zeros((11, 1)))


def test_non_numeric_rejected():
    with pytest.raises(InvalidParameterError, match="v_mps must be a real number or an array of them"):
        make_log(v_mps=["a"] * 11)


def test_nan_rejected_with_index():
    v = np.zeros(11)
    v[4] = np.nan
    with pytest.raises(DataError, match=r"v_mps must be finite; 1 non-finite value\(s\), first at index 4"):
        make_log(v_mps=v)


@pytest.mark.parametrize("which", ["time_s", "accel_time_s"])
def test_time_must_increase(which):
    log = make_log()
    t = np.array(getattr(log, which))
    t[3] = t[2]
    with pytest.raises(DataError, match=f"{which} must be strictly increasing; 1 step.*first at index 3"):
        dataclasses.replace(log, **{which: t})


def test_empty_stream_rejected():
    with pytest.raises(DataError, match="time_s is empty"):
        InteractionLog([], [], [], [], [], [0.0], [9.8])
    with pytest.raises(DataError, match="accel_time_s is empty"):
        InteractionLog([0.0], [0], [0], [0], [0], [], [])


def test_pose_and_ground_validation():
    with pytest.raises(InvalidParameterError, match=r"pose_xyh must have shape \(11, 3\)"):
        make_log(pose_xyh=np.zeros((11, 2)))
    pose = np.zeros((11, 3))
    pose[2, 1] = np.inf
    with pytest.raises(DataError, match="pose_xyh must be finite.*first at index 2"):
        make_log(pose_xyh=pose)
    with pytest.raises(InvalidParameterError, match="ground must hold str labels"):
        make_log(ground=np.arange(11))
    with pytest.raises(InvalidParameterError, match="ground must be a 1-D array of 11 labels"):
        make_log(ground=["a"] * 3)
    with pytest.raises(DataError, match="non-empty; first empty label at index 1"):
        make_log(ground=["a", ""] + ["a"] * 9)
    log = make_log(ground=np.array(["a"] * 11, dtype=object))
    assert log.ground.dtype.kind == "U" and not log.ground.flags.writeable


def test_ground_labels_from_meta_or_samples():
    log = make_log()
    assert log.ground_labels.tolist() == ["sand"] * 11
    log2 = make_log(ground=["grass"] * 11)
    assert log2.ground_labels.tolist() == ["grass"] * 11
    log3 = make_log(meta=LogMeta())
    assert log3.ground_labels is None


# ------------------------------------------------------------------ accel_on
def test_accel_on_interpolates_exactly():
    log = make_log()
    t = np.array([0.0, 0.005, 0.333, 1.0])
    np.testing.assert_allclose(log.accel_on(t), 9.81 + t, rtol=0, atol=1e-12)
    assert log.accel_on(np.zeros((2, 2))).shape == (2, 2)


def test_accel_on_refuses_extrapolation():
    log = make_log()
    with pytest.raises(DataError, match=r"1 timestamp\(s\) outside the acceleration record.*first at index 1"):
        log.accel_on([0.5, 1.5])
    with pytest.raises(DataError, match="outside the acceleration record"):
        log.accel_on([np.nan])


# ------------------------------------------------------------------ resample
def test_resample_linear_on_overlap_grid():
    # accel covers only [0.2, 0.8]: the new grid must be that overlap
    ta = 0.2 + np.arange(61) * 0.01
    log = make_log(accel_time_s=ta, accel_z_mps2=9.81 + ta, m=61)
    r = log.resample(50.0)
    assert r.time_s[0] == pytest.approx(0.2) and r.time_s[-1] == pytest.approx(0.8)
    np.testing.assert_allclose(np.diff(r.time_s), 0.02, atol=1e-12)
    np.testing.assert_allclose(r.v_mps, r.time_s, atol=1e-12)
    np.testing.assert_allclose(r.omega_radps, 2 * r.time_s, atol=1e-12)
    np.testing.assert_allclose(r.current_left_a, 1 + r.time_s, atol=1e-12)
    np.testing.assert_allclose(r.current_right_a, 3 - r.time_s, atol=1e-12)
    # acceleration kept at its own rate, covering the new drive span
    assert r.accel_rate_hz == pytest.approx(100.0)
    assert r.accel_time_s[0] <= r.time_s[0] and r.accel_time_s[-1] >= r.time_s[-1]
    r.accel_on(r.time_s)  # every new drive time is inside the acceleration record
    assert "resampled drive stream to 50 Hz (linear)" in r.meta.notes


def test_resample_previous_holds():
    log = make_log()
    r = log.resample(40.0, method="previous")
    expected = np.floor(r.time_s * 10 + 1e-9) / 10
    np.testing.assert_allclose(r.v_mps, expected, atol=1e-12)
    assert len(r) == 41


def test_resample_heading_wraps_and_ground_held():
    n = 5
    heading = np.array([3.0, 3.1, -3.1, -3.0, -2.9])  # crosses +pi
    pose = np.column_stack([np.arange(n), np.zeros(n), heading])
    log = make_log(n=n, drive_dt=1.0, m=5, accel_dt=1.0, pose_xyh=pose, ground=["a", "a", "b", "b", "c"])
    r = log.resample(2.0)
    h = r.pose_xyh[:, 2]
    assert np.all((h > -np.pi) & (h <= np.pi))
    # midpoint between 3.1 and -3.1 (through pi) is pi, not 0
    assert abs(abs(h[3]) - np.pi) < 1e-9
    np.testing.assert_allclose(r.pose_xyh[:, 0], r.time_s)
    assert r.ground.tolist() == ["a", "a", "a", "a", "b", "b", "b", "b", "c"]


def test_resample_errors():
    log = make_log()
    with pytest.raises(InvalidParameterError, match=r"rate_hz must be > 0, got 0\.0"):
        log.resample(0.0)
    with pytest.raises(UnknownNameError, match="method must be one of"):
        log.resample(10.0, method="cubic")
    disjoint = make_log(accel_time_s=5 + np.arange(3) * 0.01, accel_z_mps2=np.zeros(3), m=3)
    with pytest.raises(DataError, match="do not overlap"):
        disjoint.resample(10.0)


# ------------------------------------------------------------------ slice / concatenate
def test_slice_half_open():
    log = make_log()
    s = log.slice(0.2, 0.5)
    np.testing.assert_allclose(s.time_s, [0.2, 0.3, 0.4])
    assert s.accel_time_s[0] == pytest.approx(0.2) and s.accel_time_s[-1] == pytest.approx(0.49)
    with pytest.raises(InvalidParameterError, match="t1_s must be > t0_s"):
        log.slice(0.5, 0.5)
    with pytest.raises(InvalidParameterError, match="t0_s must be finite, got nan"):
        log.slice(np.nan, 1.0)
    with pytest.raises(DataError, match="holds no drive sample"):
        log.slice(0.01, 0.05)


def test_concatenate_shifted_runs():
    a = make_log()
    b = make_log(ground=["gravel"] * 11).shifted(2.0)
    joined = InteractionLog.concatenate([a, b])
    assert len(joined) == 22
    np.testing.assert_allclose(joined.time_s[11:], a.time_s + 2.0)
    assert joined.ground.tolist() == ["sand"] * 11 + ["gravel"] * 11  # a contributes its run label
    assert joined.meta.ground_label == "sand"
    assert joined.meta.robot == "testbot"


def test_concatenate_errors():
    a = make_log()
    with pytest.raises(DataError, match=r"logs\[1\] starts at t=0 s.*shift it"):
        InteractionLog.concatenate([a, a])
    other = make_log(meta=LogMeta(robot="other")).shifted(5)
    with pytest.raises(DataError, match="meta.robot='other' differs"):
        InteractionLog.concatenate([a, other])
    posed = make_log(pose_xyh=np.zeros((11, 3))).shifted(5)
    with pytest.raises(DataError, match="pose_xyh present in logs"):
        InteractionLog.concatenate([a, posed])
    with pytest.raises(InvalidParameterError, match="at least one"):
        InteractionLog.concatenate([])
    with pytest.raises(InvalidParameterError, match=r"logs\[0\] must be an InteractionLog"):
        InteractionLog.concatenate([3])


# ------------------------------------------------------------------ gaps
def test_split_at_gaps_no_gap_returns_self():
    log = make_log()
    assert log.split_at_gaps() == [log]


def test_split_at_gaps_drive_gap(caplog):
    t = np.r_[np.arange(10) * 0.1, 3.0 + np.arange(10) * 0.1]  # gap 0.9 -> 3.0 s
    ta = np.arange(400) * 0.01  # continuous IMU, samples inside the gap get dropped
    log = make_log(time_s=t, v_mps=t, omega_radps=t, current_left_a=t, current_right_a=t,
                   accel_time_s=ta, accel_z_mps2=np.ones(400), n=20, m=400)
    with pytest.warns(DataRepairWarning, match="1 gap"):
        pieces = log.split_at_gaps()
    assert [len(p) for p in pieces] == [10, 10]
    assert pieces[0].time_s[-1] == pytest.approx(0.9) and pieces[1].time_s[0] == pytest.approx(3.0)
    assert pieces[0].accel_time_s[-1] <= 0.9 + 1e-12 and pieces[1].accel_time_s[0] >= 3.0 - 1e-12
    dropped = 400 - sum(p.accel_time_s.size for p in pieces)
    assert dropped == int(np.sum((ta > 0.9 + 1e-9) & (ta < 3.0 - 1e-9)))
    with pytest.raises(InvalidParameterError, match=r"gap_factor must be > 1, got 1\.0"):
        log.split_at_gaps(gap_factor=1.0)
    assert DEFAULT_GAP_FACTOR > 1
