"""Tests of energy.io.cleaning: the stream checks every reader shares (repairs, gaps, units, timing)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from energy.io import MAX_RUN_DURATION_S, MAX_STREAM_RATE_HZ, MIN_STREAM_RATE_HZ, REPAIRS
from energy.io.cleaning import check_current, check_timing, clean_stream, parse_repair
from terrain import DataError, DataRepairWarning, UnitError, UnknownNameError


def test_timing_bounds_pass_real_rates_and_refuse_wrong_time_units():
    # BorealTC: 6.5 Hz drive over 277 s and a 100 Hz IMU pass comfortably
    check_timing("pro.csv", "drive stream", np.arange(1800) / 6.5)
    check_timing("imu.csv", "IMU stream", np.arange(27_754) / 100.0)
    check_timing("one.csv", "drive stream", np.array([3.0]))  # one sample has no rate
    assert MIN_STREAM_RATE_HZ == 0.5 and MAX_STREAM_RATE_HZ == 10_000.0 and MAX_RUN_DURATION_S == 86_400.0
    with pytest.raises(UnitError, match=r"pro\.csv: drive stream: median rate 0\.0065 Hz is below the plausible 0.5 Hz"):
        check_timing("pro.csv", "drive stream", np.arange(60) * (1000.0 / 6.5))  # ms read as s
    with pytest.raises(UnitError, match=r"imu\.csv: IMU stream: median rate 1e\+05 Hz is above the plausible 10000 Hz"):
        check_timing("imu.csv", "IMU stream", np.arange(100) * 1e-5)  # s declared as ms
    with pytest.raises(UnitError, match=r"spans 1\.728e\+05 s, longer than the plausible 86400 s \(one day\)"):
        check_timing("long.csv", "drive stream", np.append(np.arange(0.0, 20.0, 0.5), 172_800.0))


def test_timing_messages_round_numbers_for_people():
    t = np.arange(50) / 0.49000000000001066
    with pytest.raises(UnitError) as info:
        check_timing("x.csv", "drive stream", t)
    message = str(info.value)
    assert "0.49 Hz" in message
    assert not re.search(r"\d\.\d{6,}", message)


def test_current_unit_messages_round_numbers():
    with pytest.raises(UnitError, match=r"median \|I\| = 1500 A") as info:
        check_current("x.csv", "curL", np.full(10, 1500.000000000001), "A")
    assert "1500.000000000001" not in str(info.value)


def test_parse_repair_and_clean_stream_rules():
    assert parse_repair("sort") == {"sort"} and parse_repair(REPAIRS) == set(REPAIRS)
    with pytest.raises(UnknownNameError, match=r"repair must name only"):
        parse_repair(["sort", "guess"])
    t = np.array([0.0, 0.1, 0.1, 0.3, 0.2])
    with pytest.raises(DataError, match=r"s: x: timestamps are not sorted; 1 step\(s\) go backwards, first at index 4 "
                                        r"\(t=0\.2 s after t=0\.3 s\)"):
        clean_stream("s", "x", t, {"a": np.arange(5.0)}, frozenset(), False, 5.0)
    with pytest.warns(DataRepairWarning) as record:
        tt, cols, _ = clean_stream("s", "x", t, {"a": np.arange(5.0)}, frozenset(REPAIRS), False, 5.0)
    assert [str(w.message) for w in record] == [
        "s: x: sorted timestamps (1 backward step(s))",
        "s: x: dropped 1 sample(s) with a duplicated timestamp",
    ]
    np.testing.assert_array_equal(tt, [0.0, 0.1, 0.2, 0.3])
    np.testing.assert_array_equal(cols["a"], [0.0, 1.0, 4.0, 3.0])
    with pytest.raises(DataError, match=r"has no samples"):
        clean_stream("s", "x", np.zeros(0), {}, frozenset(), False, 5.0)
