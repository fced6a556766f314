"""energy.logs.arrays: validation of an interaction log's stream arrays, pose and ground labels."""

from __future__ import annotations

import numpy as np
import pytest

from energy.logs.arrays import (
    DRIVE_FIELDS,
    IMU_FIELDS,
    OPTIONAL_FIELDS,
    check_increasing,
    ground_array,
    log_vector,
    pose_array,
    stream_vector,
)
from terrain import DataError, InvalidParameterError


def test_field_names():
    assert DRIVE_FIELDS[:2] == ("v_mps", "omega_radps") and IMU_FIELDS == ("accel_z_mps2", "gyro_z_radps")
    assert set(OPTIONAL_FIELDS) <= set(DRIVE_FIELDS) | set(IMU_FIELDS)
    assert "v_mps" not in OPTIONAL_FIELDS and "accel_z_mps2" not in OPTIONAL_FIELDS


def test_log_vector_is_a_read_only_float_copy():
    src = np.array([1, 2, 3])
    out = log_vector("v_mps", src)
    assert out.dtype == np.float64 and not out.flags.writeable
    src[0] = 9
    assert out.tolist() == [1.0, 2.0, 3.0]


def test_log_vector_errors():
    with pytest.raises(DataError, match=r"v_mps must be finite; 2 non-finite value\(s\), first at index 1 \(nan\)"):
        log_vector("v_mps", [0.0, np.nan, np.inf])
    with pytest.raises(InvalidParameterError, match="v_mps"):
        log_vector("v_mps", np.zeros((2, 2)))
    with pytest.raises(InvalidParameterError, match="v_mps"):
        log_vector("v_mps", ["a", "b"])


def test_stream_vector_checks_length_and_optional_fields():
    assert stream_vector("gyro_z_radps", None, 3, "accel_time_s") is None
    assert stream_vector("v_mps", [1, 2, 3], 3, "time_s").tolist() == [1.0, 2.0, 3.0]
    with pytest.raises(InvalidParameterError, match="v_mps is required, got None"):
        stream_vector("v_mps", None, 3, "time_s")
    with pytest.raises(InvalidParameterError, match=r"accel_z_mps2 must have the length of accel_time_s \(3\), got 2"):
        stream_vector("accel_z_mps2", [1.0, 2.0], 3, "accel_time_s")


def test_check_increasing():
    check_increasing("time_s", np.array([0.0, 0.1, 0.3]))
    check_increasing("time_s", np.array([5.0]))
    with pytest.raises(DataError, match="time_s is empty"):
        check_increasing("time_s", np.zeros(0))
    with pytest.raises(DataError, match=r"time_s must be strictly increasing; 2 step\(s\) are not, first at index 2 "
                                        r"\(t=0.1 after t=0.1\)"):
        check_increasing("time_s", np.array([0.0, 0.1, 0.1, 0.05]))


def test_pose_array():
    pose = pose_array([[0, 0, 0], [1, 2, 3]], 2)
    assert pose.dtype == np.float64 and pose.shape == (2, 3) and not pose.flags.writeable
    with pytest.raises(InvalidParameterError, match=r"pose_xyh must have shape \(2, 3\), got \(2, 2\)"):
        pose_array(np.zeros((2, 2)), 2)
    with pytest.raises(DataError, match=r"pose_xyh must be finite; 1 row\(s\) are not, first at index 1"):
        pose_array([[0, 0, 0], [0, np.nan, np.nan]], 2)


def test_ground_array():
    g = ground_array(np.array(["a", "b"], dtype=object), 2)
    assert g.dtype.kind == "U" and g.tolist() == ["a", "b"] and not g.flags.writeable
    with pytest.raises(InvalidParameterError, match=r"ground must be a 1-D array of 3 labels, got shape \(2,\)"):
        ground_array(["a", "b"], 3)
    with pytest.raises(InvalidParameterError, match="ground must hold str labels"):
        ground_array([1, 2], 2)
    with pytest.raises(DataError, match="ground labels must be non-empty; first empty label at index 1"):
        ground_array(["a", ""], 2)
