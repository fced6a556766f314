"""Tests of energy.io.borealtc: the BorealTC run folders (imu_NN.csv + pro_NN.csv)."""

from __future__ import annotations

import logging
import re
import shutil
import warnings

import numpy as np
import pytest
from energy_io_samples import (
    BOREALTC_FIX,
    copy_run,
    edit_lines,
    fuzz_settings,
    mutate_bytes,
    read_rows,
    shared_data_or_skip,
)
from hypothesis import given
from hypothesis import strategies as st

from energy import read_borealtc
from energy.io import LogCleaning, read_borealtc_run
from terrain import (
    DataError,
    DataRepairWarning,
    FileFormatError,
    InvalidParameterError,
    TerrawattError,
    UnitError,
    UnknownNameError,
)


# =========================================================================== BorealTC
def test_borealtc_fixture_values_and_alignment():
    logs = read_borealtc(BOREALTC_FIX)
    assert [log.meta.ground_label for log in logs] == ["asphalt", "snow"]
    for log, ground, nn in zip(logs, ("ASPHALT", "SNOW"), ("00", "05")):
        _, pro = read_rows(BOREALTC_FIX / ground / f"pro_{nn}.csv")
        _, imu = read_rows(BOREALTC_FIX / ground / f"imu_{nn}.csv")
        t0, t1 = max(pro[0, 0], imu[0, 0]), min(pro[-1, 0], imu[-1, 0])
        keep = (pro[:, 0] >= t0) & (pro[:, 0] <= t1)
        np.testing.assert_array_equal(log.time_s, pro[keep, 0])
        np.testing.assert_array_equal(log.current_left_a, pro[keep, 1])
        np.testing.assert_array_equal(log.current_right_a, pro[keep, 2])
        np.testing.assert_allclose(log.v_mps, (pro[keep, 3] + pro[keep, 4]) / 2, rtol=0, atol=1e-15)
        np.testing.assert_allclose(log.omega_radps, (pro[keep, 4] - pro[keep, 3]) / 0.555, rtol=0, atol=1e-14)
        # IMU: the samples bracketing the kept drive span, az unchanged
        ia = np.flatnonzero(imu[:, 0] <= log.time_s[0])[-1]
        ib = np.flatnonzero(imu[:, 0] >= log.time_s[-1])[0]
        np.testing.assert_array_equal(log.accel_time_s, imu[ia : ib + 1, 0])
        np.testing.assert_array_equal(log.accel_z_mps2, imu[ia : ib + 1, 6])
        log.accel_on(log.time_s)
        assert log.meta.velocity_source == "measured"
        assert log.meta.track_width_m == 0.555
        assert "aligned on the overlap" in log.meta.notes
    # the asphalt fixture's drive file outlasts its IMU file: drive samples were cut
    _, pro = read_rows(BOREALTC_FIX / "ASPHALT" / "pro_00.csv")
    assert len(logs[0]) < pro.shape[0]
    # the snow fixture's IMU outlasts its drive file: IMU samples were cut
    _, imu = read_rows(BOREALTC_FIX / "SNOW" / "imu_05.csv")
    assert logs[1].accel_time_s.size < imu.shape[0]


def test_borealtc_track_width_scales_omega():
    imu, pro = BOREALTC_FIX / "SNOW" / "imu_05.csv", BOREALTC_FIX / "SNOW" / "pro_05.csv"
    a = read_borealtc_run(imu, pro)
    b = read_borealtc_run(imu, pro, track_width_m=1.11, ground_label="snow")
    np.testing.assert_allclose(b.omega_radps * 2, a.omega_radps, rtol=1e-12)
    np.testing.assert_array_equal(a.v_mps, b.v_mps)
    assert a.meta.ground_label is None and b.meta.ground_label == "snow"
    with pytest.raises(InvalidParameterError, match="track_width_m must be > 0"):
        read_borealtc_run(imu, pro, track_width_m=-1.0)


def test_borealtc_grounds_selection(tmp_path):
    logs = read_borealtc(BOREALTC_FIX, grounds=["snow"])
    assert [log.meta.ground_label for log in logs] == ["snow"]
    with pytest.raises(UnknownNameError, match=r"grounds \['gravel'\] have no folder.*available: \['ASPHALT', 'SNOW'\]"):
        read_borealtc(BOREALTC_FIX, grounds=["gravel"])
    with pytest.raises(FileFormatError, match="does not exist or is not a directory"):
        read_borealtc(tmp_path / "nowhere")
    with pytest.raises(DataError, match="no BorealTC runs"):
        read_borealtc(tmp_path)
    with pytest.raises(InvalidParameterError, match="do not pass ground_label"):
        read_borealtc(BOREALTC_FIX, ground_label="x")
    with pytest.raises(InvalidParameterError, match="grounds must be a folder name or an iterable of folder names, got 5"):
        read_borealtc(BOREALTC_FIX, grounds=5)


def test_borealtc_unpaired_file(tmp_path):
    imu, _ = copy_run(tmp_path)
    shutil.copy(imu, tmp_path / "ASPHALT" / "imu_07.csv")
    with pytest.raises(DataError, match=r"without their imu/pro partner.*imu_07\.csv"):
        read_borealtc(tmp_path)


def test_borealtc_unsorted_raises_then_sort_repair(tmp_path, caplog):
    imu, pro = copy_run(tmp_path)
    reference = read_borealtc_run(imu, pro)
    edit_lines(pro, lambda ls: [ls[0], ls[1], ls[3], ls[2], *ls[4:]])
    with pytest.raises(DataError, match=r"drive stream: timestamps are not sorted; 1 step\(s\) go backwards, first at index 2"):
        read_borealtc_run(imu, pro)
    with caplog.at_level(logging.WARNING, logger="energy.io"):
        with pytest.warns(DataRepairWarning, match=r"sorted timestamps \(1 backward step"):
            fixed = read_borealtc_run(imu, pro, cleaning=LogCleaning(repair=("sort",)))
    assert any("sorted timestamps" in r.getMessage() for r in caplog.records)
    np.testing.assert_array_equal(fixed.time_s, reference.time_s)
    np.testing.assert_array_equal(fixed.current_left_a, reference.current_left_a)


def test_borealtc_duplicates_raise_then_drop(tmp_path):
    imu, pro = copy_run(tmp_path)
    reference = read_borealtc_run(imu, pro)
    edit_lines(imu, lambda ls: ls[:6] + [ls[5]] + ls[6:])
    with pytest.raises(DataError, match=r"IMU stream: 1 duplicated timestamp\(s\), first at index 5 \(t=0.04 s\)"):
        read_borealtc_run(imu, pro)
    with pytest.warns(DataRepairWarning, match=r"dropped 1 sample\(s\) with a duplicated timestamp"):
        fixed = read_borealtc_run(imu, pro, cleaning=LogCleaning(repair="drop_duplicates"))
    np.testing.assert_array_equal(fixed.accel_time_s, reference.accel_time_s)


def test_borealtc_nan_raises_then_interpolates(tmp_path):
    imu, pro = copy_run(tmp_path)
    _, raw = read_rows(pro)
    edit_lines(pro, lambda ls: ls[:4] + [",".join(ls[4].split(",")[:2] + ["", *ls[4].split(",")[3:]])] + ls[5:])
    with pytest.raises(DataError, match=r"column 'curR' has 1 missing or non-finite value\(s\), first at index 3"):
        read_borealtc_run(imu, pro)
    with pytest.warns(DataRepairWarning, match="interpolated 1 missing value"):
        log = read_borealtc_run(imu, pro, cleaning=LogCleaning(repair=["interpolate_nans"]))
    t = raw[:, 0]
    expected = raw[2, 2] + (raw[4, 2] - raw[2, 2]) * (t[3] - t[2]) / (t[4] - t[2])
    assert log.current_right_a[3] == pytest.approx(expected, abs=1e-12)


def test_borealtc_literal_nan_token(tmp_path):
    imu, pro = copy_run(tmp_path)
    edit_lines(imu, lambda ls: ls[:10] + [ls[10].rsplit(",", 1)[0] + ",nan"] + ls[11:])
    with pytest.raises(DataError, match=r"IMU stream: column 'az' has 1 missing.*index 9 \(t=0.09 s\)"):
        read_borealtc_run(imu, pro)


def test_borealtc_nan_time_never_repaired(tmp_path):
    imu, pro = copy_run(tmp_path)
    edit_lines(pro, lambda ls: ls[:3] + ["," + ls[3].split(",", 1)[1]] + ls[4:])
    with pytest.raises(DataError, match=r"1 timestamp\(s\) are missing.*never repaired"):
        read_borealtc_run(imu, pro, cleaning=LogCleaning(repair=("interpolate_nans",)))


def test_borealtc_gap_raises_or_allowed(tmp_path):
    imu, pro = copy_run(tmp_path)
    edit_lines(imu, lambda ls: ls[:40] + ls[100:])  # 0.6 s hole in a 100 Hz stream
    with pytest.raises(DataError, match=r"IMU stream: 1 gap\(s\) longer than 5 median periods.*allow_gaps=True"):
        read_borealtc_run(imu, pro)
    log = read_borealtc_run(imu, pro, cleaning=LogCleaning(allow_gaps=True))
    with pytest.warns(DataRepairWarning, match="split_at_gaps"):
        pieces = log.split_at_gaps()
    assert len(pieces) == 2
    assert pieces[0].accel_time_s[-1] < pieces[1].accel_time_s[0]


def test_borealtc_missing_column_and_empty_files(tmp_path):
    imu, pro = copy_run(tmp_path)
    edit_lines(pro, lambda ls: [ls[0].replace("curR", "current_right")] + ls[1:])
    with pytest.raises(DataError, match=r"missing column\(s\) \['curR'\]"):
        read_borealtc_run(imu, pro)
    pro.write_text("")
    with pytest.raises(DataError, match="is empty: no header line"):
        read_borealtc_run(imu, pro)
    pro.write_text("time,curL,curR,velL,velR\n")
    with pytest.raises(DataError, match="header .* but no data rows"):
        read_borealtc_run(imu, pro)
    with pytest.raises(FileFormatError, match="does not exist"):
        read_borealtc_run(imu, tmp_path / "missing.csv")


def test_borealtc_garbage_and_ragged_rows(tmp_path):
    imu, pro = copy_run(tmp_path)
    edit_lines(pro, lambda ls: ls[:2] + [ls[2].replace(ls[2].split(",")[1], "abc", 1)] + ls[3:])
    with pytest.raises(FileFormatError, match=r"line 3, column 'curL': 'abc' is not a number"):
        read_borealtc_run(imu, pro)
    imu2, pro2 = copy_run(tmp_path / "b")
    edit_lines(pro2, lambda ls: ls[:5] + ["0.9,1.0"] + ls[5:])
    with pytest.raises(FileFormatError, match=r"line 6: 2 field\(s\), expected 5"):
        read_borealtc_run(imu2, pro2)


def test_borealtc_milliamps_declared_as_amps(tmp_path):
    imu, pro = copy_run(tmp_path)

    def to_ma(lines):
        out = [lines[0]]
        for line in lines[1:]:
            f = line.split(",")
            f[1], f[2] = str(round(float(f[1]) * 1000)), str(round(float(f[2]) * 1000))
            out.append(",".join(f))
        return out

    edit_lines(pro, to_ma)
    with pytest.raises(UnitError, match="curL is declared in A but its values look like mA"):
        read_borealtc_run(imu, pro)
    log = read_borealtc_run(imu, pro, cleaning=LogCleaning(check_units=False))  # explicit opt-out
    assert log.current_left_a.max() > 1000


def test_borealtc_speed_in_mm_per_s(tmp_path):
    imu, pro = copy_run(tmp_path)

    def to_mm(lines):
        out = [lines[0]]
        for line in lines[1:]:
            f = line.split(",")
            f[3], f[4] = str(float(f[3]) * 1000), str(float(f[4]) * 1000)
            out.append(",".join(f))
        return out

    edit_lines(pro, to_mm)
    with pytest.raises(UnitError, match=r"\|velL\| reaches .* m/s .*look like mm/s or cm/s"):
        read_borealtc_run(imu, pro)


def test_unknown_repair_name():
    imu, pro = BOREALTC_FIX / "SNOW" / "imu_05.csv", BOREALTC_FIX / "SNOW" / "pro_05.csv"
    with pytest.raises(UnknownNameError, match=r"repair must name only .* unknown \['fill'\]"):
        read_borealtc_run(imu, pro, cleaning=LogCleaning(repair=("fill",)))


def test_borealtc_real_data_all_runs():
    root = shared_data_or_skip()
    logs = read_borealtc(root)
    pro_files = sorted(root.glob("*/pro_*.csv"))
    assert len(logs) == len(pro_files)
    assert {log.meta.ground_label for log in logs} == {p.parent.name.lower() for p in pro_files}
    for log in logs:
        # currents are motoring-only (>= 0) and the rates are the documented ~6.5 Hz and ~100 Hz
        assert log.current_left_a.min() >= 0 and log.current_right_a.min() >= 0
        assert 5.0 < log.drive_rate_hz < 8.0 and 90.0 < log.accel_rate_hz < 110.0
        assert log.accel_time_s[0] <= log.time_s[0] and log.accel_time_s[-1] >= log.time_s[-1]
        assert 5.0 < np.median(log.accel_z_mps2) < 15.0  # gravity included



# ===================================================================== hostile input
def test_borealtc_invalid_utf8_byte_beyond_8_kib(tmp_path):
    imu, pro = copy_run(tmp_path)
    data = bytearray(imu.read_bytes())
    assert len(data) > 9000  # past the first 8 KiB read by a text decoder
    at = data.index(b"\n", 9000) + 3  # a digit of the row after byte 9000
    data[at] = 0xFF
    imu.write_bytes(bytes(data))
    line = data.count(b"\n", 0, at) + 1
    with pytest.raises(FileFormatError, match=rf"imu_00\.csv' is not a UTF-8 text CSV file: byte {at} \(line {line}\) is "
                                              r"b'\\xff'"):
        read_borealtc_run(imu, pro)
    # an early bad byte in the other file is named as well
    copy_run(tmp_path)
    pro.write_bytes(b"time,curL,curR,velL,velR\n0.0,\xc3(,1,0,0\n")
    with pytest.raises(FileFormatError, match=r"pro_00\.csv' is not a UTF-8 text CSV file: byte 29 \(line 2\)"):
        read_borealtc_run(imu, pro)


def test_borealtc_times_in_milliseconds_are_a_unit_error(tmp_path):
    imu, pro = copy_run(tmp_path)

    def to_ms(lines):
        return [lines[0]] + [",".join([repr(float(r.split(",")[0]) * 1000.0), *r.split(",")[1:]]) for r in lines[1:]]

    edit_lines(pro, to_ms)
    edit_lines(imu, to_ms)
    with pytest.raises(UnitError, match=r"pro_00\.csv: drive stream: median rate 0\.0065 Hz is below the plausible 0.5 Hz "
                                        r"of a recorded robot stream \(median step 153\.8 s\); the time unit looks wrong") as info:
        read_borealtc_run(imu, pro)
    assert not re.search(r"\d\.\d{6,}", str(info.value))  # numbers rounded for people
    log = read_borealtc_run(imu, pro, cleaning=LogCleaning(check_units=False))  # the caller may still insist
    assert log.drive_rate_hz == pytest.approx(0.0065)


def test_borealtc_imu_rate_above_10_khz_is_a_unit_error(tmp_path):
    imu, pro = copy_run(tmp_path)
    # IMU times in ms declared (read) as s would be slow; times in us read as ms are fast:
    # here every IMU step is 1e-5 s (100 kHz) while the drive file keeps its 6.5 Hz
    edit_lines(imu, lambda ls: [ls[0]] + [",".join([repr(k * 1e-5), *r.split(",")[1:]]) for k, r in enumerate(ls[1:])])
    edit_lines(pro, lambda ls: [ls[0]] + [",".join([repr(k * 1e-5 * 15), *r.split(",")[1:]]) for k, r in enumerate(ls[1:])])
    with pytest.raises(UnitError, match=r"imu_00\.csv: IMU stream: median rate 1e\+05 Hz is above the plausible 10000 Hz"):
        read_borealtc_run(imu, pro)


EDITS = st.lists(st.tuples(st.integers(0, 2), st.integers(0, 2**31), st.integers(0, 255)), min_size=1, max_size=8)
CSVISH = st.sampled_from(list(b"0123456789.,-+eE \n\r#\"nai"))


@pytest.mark.parametrize("target", ["imu", "pro"])
@fuzz_settings(60)
@given(edits=EDITS, truncate=st.one_of(st.none(), st.integers(0, 4000)))
def test_fuzz_borealtc_mutated_run_files(tmp_path, target, edits, truncate):
    """Mutated BorealTC files read or raise a TerrawattError, never another exception.

    Long run: ``TERRAWATT_FUZZ_EXAMPLES=20 python -m pytest -q tests/energy -k fuzz``.
    """
    src = BOREALTC_FIX / "SNOW" / f"{target}_05.csv"
    data = mutate_bytes(src.read_bytes(), edits)
    if truncate is not None:
        data = data[:truncate]
    folder = tmp_path / "SNOW"
    folder.mkdir(exist_ok=True)
    for name in ("imu_05.csv", "pro_05.csv"):
        shutil.copy(BOREALTC_FIX / "SNOW" / name, folder / name)
    (folder / f"{target}_05.csv").write_bytes(data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataRepairWarning)  # repairs were asked for
        try:
            read_borealtc(tmp_path, cleaning=LogCleaning(repair=("sort", "drop_duplicates", "interpolate_nans"),
                                                         allow_gaps=True))
            read_borealtc(tmp_path)
        except TerrawattError:
            pass


@fuzz_settings(60)
@given(data=st.one_of(st.binary(max_size=600), st.lists(CSVISH, max_size=600).map(bytes)))
def test_fuzz_borealtc_random_bytes(tmp_path, data):
    """Random bytes as a BorealTC drive file read or raise a TerrawattError.

    Long run: ``TERRAWATT_FUZZ_EXAMPLES=20 python -m pytest -q tests/energy -k fuzz``.
    """
    imu = BOREALTC_FIX / "SNOW" / "imu_05.csv"
    pro = tmp_path / "pro_05.csv"
    pro.write_bytes(b"time,curL,curR,velL,velR\n" + data)
    try:
        read_borealtc_run(imu, pro)
    except TerrawattError:
        pass
    pro.write_bytes(data)
    try:
        read_borealtc_run(imu, pro, cleaning=LogCleaning(check_units=False))
    except TerrawattError:
        pass
