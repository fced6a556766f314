"""Tests of energy.io.bag_align: a bag's current, velocity and IMU streams on one drive clock."""

from __future__ import annotations

import numpy as np
import pytest

from energy.io.bag_align import CurrentStreams, align_streams
from terrain import DataError


def imu(t0: float = -0.05, t1: float = 1.05, step: float = 0.01) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    t = np.round(np.arange(t0, t1 + step / 2, step), 9)
    return t, {"accel_z": np.full(t.size, 9.81)}


def commands(t, v, omega=None) -> tuple[np.ndarray, dict[str, np.ndarray], bool]:
    v = np.asarray(v, float)
    return np.asarray(t, float), {"v": v, "omega": np.zeros(v.size) if omega is None else np.asarray(omega, float)}, False


def test_commands_are_held_on_the_current_times_and_zeroed_after_the_timeout():
    tc = np.arange(11) * 0.1
    cur = CurrentStreams(tc, np.full(11, 2.0), tc, np.full(11, 3.0), voltage_v=np.full(11, 24.0))
    notes: list[str] = []
    out = align_streams("b", cur, commands([0.0, 0.35], [1.0, 0.5]), imu(), 0.5, 10.0, notes)
    np.testing.assert_array_equal(out["time_s"], tc)
    # 1.0 from t=0, 0.5 from t=0.35, 0 once 0.5 s have passed since 0.35 s (t > 0.85)
    np.testing.assert_allclose(out["v_mps"], [1.0, 1.0, 1.0, 1.0, 0.5, 0.5, 0.5, 0.5, 0.5, 0.0, 0.0])
    assert out["current_left_a"].tolist() == [2.0] * 11 and out["current_right_a"].tolist() == [3.0] * 11
    assert out["battery_voltage_v"].tolist() == [24.0] * 11
    assert "zero after 0.5 s without one (2 drive sample(s))" in " ".join(notes)
    assert out["gyro_z_radps"] is None


def test_a_right_current_on_its_own_topic_is_interpolated_onto_the_left_times():
    tl = np.arange(6) * 0.2
    tr = np.arange(11) * 0.1
    cur = CurrentStreams(tl, np.full(6, 1.0), tr, tr * 10.0)
    out = align_streams("b", cur, commands([0.0], [0.3]), imu(), None, 10.0, [])
    np.testing.assert_allclose(out["current_right_a"], tl * 10.0)
    np.testing.assert_array_equal(out["v_mps"], np.full(6, 0.3))


def test_commands_only_give_a_grid_at_the_drive_rate_over_the_overlap():
    notes: list[str] = []
    out = align_streams("b", None, commands([0.0, 0.5], [0.2, 0.4]), imu(0.0, 1.0), None, 4.0, notes)
    np.testing.assert_allclose(out["time_s"], [0.0, 0.25, 0.5, 0.75, 1.0])
    np.testing.assert_allclose(out["v_mps"], [0.2, 0.2, 0.4, 0.4, 0.4])
    assert out["current_left_a"] is None and out["battery_voltage_v"] is None
    assert "drive stream on a 4 Hz grid over the overlap" in notes


def test_measured_odometry_is_interpolated_and_the_heading_wrapped():
    tv = np.array([0.0, 1.0])
    vc = {"v": np.array([0.0, 1.0]), "omega": np.array([0.0, 2.0]), "x": np.array([0.0, 2.0]),
          "y": np.array([1.0, 1.0]), "heading": np.array([3.0, 3.0 + 0.4 - 2 * np.pi])}  # crosses +pi
    out = align_streams("b", None, (tv, vc, True), imu(), None, 10.0, [])
    np.testing.assert_array_equal(out["time_s"], tv)  # on the odometry's own times
    np.testing.assert_allclose(out["v_mps"], [0.0, 1.0])
    np.testing.assert_allclose(out["pose_xyh"][:, :2], [[0.0, 1.0], [2.0, 1.0]])
    np.testing.assert_allclose(out["pose_xyh"][:, 2], [3.0, 3.4 - 2 * np.pi])
    tc = np.array([0.0, 0.5, 1.0])  # on the currents' times: interpolated across the wrap, not through 0
    mid = align_streams("b", CurrentStreams(tc, np.ones(3), tc, np.ones(3)), (tv, vc, True), imu(), None, 10.0, [])
    np.testing.assert_allclose(mid["pose_xyh"][:, 2], [3.0, 3.2 - 2 * np.pi, 3.4 - 2 * np.pi])  # 3.2 rad is -3.08 rad in (-pi, pi]
    np.testing.assert_allclose(mid["omega_radps"], [0.0, 1.0, 2.0])


def test_the_imu_keeps_the_samples_bracketing_the_drive_span():
    tc = np.array([0.3, 0.4, 0.5])
    cur = CurrentStreams(tc, np.ones(3), tc, np.ones(3))
    notes: list[str] = []
    out = align_streams("b", cur, commands([0.0], [0.1]), imu(0.0, 1.0, 0.25), None, 10.0, notes)
    np.testing.assert_allclose(out["accel_time_s"], [0.25, 0.5])
    assert "3 IMU sample(s) outside the kept drive span" in notes[-1]


def test_streams_that_do_not_overlap_are_a_data_error():
    tc = np.arange(5) * 0.1 + 10.0
    cur = CurrentStreams(tc, np.ones(5), tc, np.ones(5))
    with pytest.raises(DataError, match=r"bag\.db3: the streams do not overlap \(current \[10, 10\.4\] s, IMU "):
        align_streams("bag.db3", cur, commands([0.0], [0.1]), imu(), None, 10.0, [])
