"""energy.logs.joining: the checks and the fields of a concatenation of interaction logs."""

from __future__ import annotations

import numpy as np
import pytest
from log_samples import make_log

from energy import LogMeta
from energy.logs.joining import concatenated_fields, join_notes
from terrain import DataError


def test_join_notes_skips_empty_parts():
    assert join_notes("read from a.csv", "", "resampled") == "read from a.csv; resampled"
    assert join_notes() == "" and join_notes("", "") == ""


def test_fields_of_two_runs():
    a = make_log(meta=LogMeta(robot="r", source="a.csv", ground_label="sand", notes="n1"))
    b = make_log(meta=LogMeta(robot="r", source="b.csv", ground_label="snow", gravity_removed=True),
                 ground=["snow"] * 11).shifted(2.0)
    out = concatenated_fields([a, b])
    np.testing.assert_array_equal(out["time_s"], np.r_[a.time_s, b.time_s])
    np.testing.assert_array_equal(out["current_left_a"], np.r_[a.current_left_a, b.current_left_a])
    assert out["pose_xyh"] is None and out["battery_voltage_v"] is None
    assert out["ground"].tolist() == ["sand"] * 11 + ["snow"] * 11  # a contributes its run label
    meta = out["meta"]
    assert meta.source == "a.csv; b.csv" and meta.ground_label is None  # two run labels: none for the whole
    assert meta.notes == "n1; concatenation of 2 logs" and meta.gravity_removed is True


def test_one_run_label_is_kept_and_no_per_sample_ground_stays_none():
    a = make_log(meta=LogMeta(robot="r"))
    out = concatenated_fields([a, make_log(meta=LogMeta(robot="r")).shifted(5.0)])
    assert out["ground"] is None and out["meta"].ground_label is None
    same = concatenated_fields([make_log(), make_log().shifted(5.0)])
    assert same["meta"].ground_label == "sand" and same["ground"] is None


def test_disagreeing_track_width_and_out_of_order_logs_are_refused():
    a = make_log(meta=LogMeta(track_width_m=0.5))
    with pytest.raises(DataError, match=r"logs\[1\].meta.track_width_m=0.6 differs from logs\[0\].meta.track_width_m=0.5"):
        concatenated_fields([a, make_log(meta=LogMeta(track_width_m=0.6)).shifted(5.0)])
    with pytest.raises(DataError, match=r"cannot concatenate: logs\[1\] starts at t=0.5 s .*shift it with .shifted"):
        concatenated_fields([make_log(), make_log().shifted(0.5)])


def test_a_stream_in_some_logs_only_is_refused():
    bare = make_log(current_left_a=None, current_right_a=None)
    with pytest.raises(DataError, match=r"current_left_a present in logs \[True, False\] .*current topics or fields"):
        concatenated_fields([make_log(), bare.shifted(5.0)])


def test_ground_in_some_logs_only_is_refused():
    labelled = make_log(meta=LogMeta(), ground=["grass"] * 11)
    unlabelled = make_log(meta=LogMeta()).shifted(5.0)
    with pytest.raises(DataError, match=r"logs \[1\] have neither per-sample ground nor meta.ground_label"):
        concatenated_fields([labelled, unlabelled])
