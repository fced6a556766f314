"""Tests of energy.readers: BorealTC CSV, generic CSV (+ writer) and ROS 1/2 bag readers."""

from __future__ import annotations

import csv
import logging
import re
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from energy import (
    InteractionLog,
    LogMeta,
    read_borealtc,
    read_borealtc_run,
    read_csv_log,
    read_rosbag,
    write_csv_log,
)
from terrain import (
    DataError,
    DataRepairWarning,
    FileFormatError,
    FormatVersionError,
    InvalidParameterError,
    OptionalDependencyError,
    UnitError,
    UnknownNameError,
)

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
BOREALTC_FIX = FIXTURES / "borealtc"
GENERIC = FIXTURES / "generic_ma.csv"
SHARED_BOREALTC = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "borealtc"
GENERIC_COLUMNS = {
    "time": "stamp_ms",
    "v": "cmd_v",
    "omega": "cmd_w",
    "current_left": "left_mA",
    "current_right": "right_mA",
    "accel_z": "acc_z",
    "ground": "label",
}
GENERIC_UNITS = {"time": "ms", "current_left": "mA", "current_right": "mA", "omega": "deg/s"}


def read_rows(path: Path) -> tuple[list[str], np.ndarray]:
    """Independent reference parse of a numeric CSV with the csv module."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], np.array([[float(x) for x in r] for r in rows[1:]])


def copy_run(tmp_path: Path, ground: str = "ASPHALT", nn: str = "00") -> tuple[Path, Path]:
    dst = tmp_path / ground
    dst.mkdir(parents=True, exist_ok=True)
    imu = shutil.copy(BOREALTC_FIX / ground / f"imu_{nn}.csv", dst)
    pro = shutil.copy(BOREALTC_FIX / ground / f"pro_{nn}.csv", dst)
    return Path(imu), Path(pro)


def edit_lines(path: Path, fn) -> None:
    lines = path.read_text().splitlines()
    path.write_text("\n".join(fn(lines)) + "\n")


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
            fixed = read_borealtc_run(imu, pro, repair=("sort",))
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
        fixed = read_borealtc_run(imu, pro, repair="drop_duplicates")
    np.testing.assert_array_equal(fixed.accel_time_s, reference.accel_time_s)


def test_borealtc_nan_raises_then_interpolates(tmp_path):
    imu, pro = copy_run(tmp_path)
    _, raw = read_rows(pro)
    edit_lines(pro, lambda ls: ls[:4] + [",".join(ls[4].split(",")[:2] + ["", *ls[4].split(",")[3:]])] + ls[5:])
    with pytest.raises(DataError, match=r"column 'curR' has 1 missing or non-finite value\(s\), first at index 3"):
        read_borealtc_run(imu, pro)
    with pytest.warns(DataRepairWarning, match="interpolated 1 missing value"):
        log = read_borealtc_run(imu, pro, repair=["interpolate_nans"])
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
        read_borealtc_run(imu, pro, repair=("interpolate_nans",))


def test_borealtc_gap_raises_or_allowed(tmp_path):
    imu, pro = copy_run(tmp_path)
    edit_lines(imu, lambda ls: ls[:40] + ls[100:])  # 0.6 s hole in a 100 Hz stream
    with pytest.raises(DataError, match=r"IMU stream: 1 gap\(s\) longer than 5 median periods.*allow_gaps=True"):
        read_borealtc_run(imu, pro)
    log = read_borealtc_run(imu, pro, allow_gaps=True)
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
    log = read_borealtc_run(imu, pro, check_units=False)  # explicit opt-out
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
        read_borealtc_run(imu, pro, repair=("fill",))


def shared_data_or_skip() -> Path:
    if not SHARED_BOREALTC.is_dir():
        pytest.skip("shared BorealTC data not found at ../shared/data/borealtc (beside the repository)")
    return SHARED_BOREALTC


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


# ========================================================================= generic CSV
def test_generic_csv_units_and_mixed_rates():
    log = read_csv_log(GENERIC, GENERIC_COLUMNS, GENERIC_UNITS, robot="rover")
    k = np.arange(11)
    np.testing.assert_allclose(log.time_s, k * 0.1, rtol=0, atol=1e-15)
    np.testing.assert_allclose(log.v_mps, 0.05 * k, atol=1e-15)
    np.testing.assert_allclose(log.omega_radps, np.deg2rad(10 * k), atol=1e-14)
    np.testing.assert_allclose(log.current_left_a, (1000 + 100 * k) / 1000, atol=1e-15)
    np.testing.assert_allclose(log.current_right_a, (1200 + 50 * k) / 1000, atol=1e-15)
    j = np.arange(51)
    np.testing.assert_allclose(log.accel_time_s, 0.02 * j, atol=1e-15)
    np.testing.assert_allclose(log.accel_z_mps2, 9.81 + 0.01 * j, atol=1e-12)
    assert log.ground.tolist() == ["grass"] * 5 + ["gravel"] * 6
    assert log.meta.robot == "rover" and log.meta.velocity_source == "commanded"
    assert "converted to SI" in log.meta.notes


def test_generic_csv_milliamps_declared_as_amps():
    units = {k: v for k, v in GENERIC_UNITS.items() if not k.startswith("current")}
    with pytest.raises(UnitError, match="left_mA is declared in A but its values look like mA"):
        read_csv_log(GENERIC, GENERIC_COLUMNS, units)


def test_generic_csv_amps_declared_as_milliamps(tmp_path):
    log = read_csv_log(GENERIC, GENERIC_COLUMNS, GENERIC_UNITS)
    path = write_csv_log(dataclass_replace_currents(log, 0.001), tmp_path / "small.csv")
    # the exported file is in A; declaring mA makes the peak 2 mA, which looks like A
    with pytest.raises(UnitError, match="declared in mA but its peak is .* look like A"):
        read_csv_log(path, units={"current_left": "mA", "current_right": "mA"})


def dataclass_replace_currents(log: InteractionLog, scale: float) -> InteractionLog:
    import dataclasses

    return dataclasses.replace(
        log, current_left_a=log.current_left_a * scale, current_right_a=log.current_right_a * scale
    )


def test_generic_csv_deg_per_s_declared_as_rad_per_s():
    units = {k: v for k, v in GENERIC_UNITS.items() if k != "omega"}
    with pytest.raises(UnitError, match=r"\|cmd_w\| reaches 100 rad/s \(index 10\).*declared 'rad/s' looks like deg/s"):
        read_csv_log(GENERIC, GENERIC_COLUMNS, units)


def test_generic_csv_accel_declared_in_g():
    with pytest.raises(UnitError, match=r"median \|acc_z\| is .* m/s\^2"):
        read_csv_log(GENERIC, GENERIC_COLUMNS, {**GENERIC_UNITS, "accel_z": "g"})


def test_generic_csv_bad_maps():
    with pytest.raises(UnknownNameError, match=r"unknown field\(s\) \['speed'\]"):
        read_csv_log(GENERIC, {**GENERIC_COLUMNS, "speed": "cmd_v"}, GENERIC_UNITS)
    with pytest.raises(UnknownNameError, match="unit 'furlong/s' is not known for field 'v'"):
        read_csv_log(GENERIC, GENERIC_COLUMNS, {**GENERIC_UNITS, "v": "furlong/s"})
    with pytest.raises(UnknownNameError, match="units given for field"):
        read_csv_log(GENERIC, GENERIC_COLUMNS, {**GENERIC_UNITS, "x": "m"})
    cols = {k: v for k, v in GENERIC_COLUMNS.items() if k != "current_right"}
    with pytest.raises(InvalidParameterError, match=r"lacks required field\(s\) \['current_right'\]"):
        read_csv_log(GENERIC, cols, {k: v for k, v in GENERIC_UNITS.items() if k != "current_right"})
    with pytest.raises(DataError, match=r"missing column\(s\) \['nope'\]"):
        read_csv_log(GENERIC, {**GENERIC_COLUMNS, "accel_z": "nope"}, GENERIC_UNITS)
    with pytest.raises(InvalidParameterError, match="all of x, y, heading or none"):
        read_csv_log(GENERIC, {**GENERIC_COLUMNS, "x": "cmd_v"}, GENERIC_UNITS)


def test_generic_csv_wheel_speeds(tmp_path):
    path = tmp_path / "wheels.csv"
    path.write_text("t,wl,wr,il,ir,az\n0,0.1,0.3,1.5,2.5,9.8\n0.5,0.2,0.2,1.6,2.4,9.7\n1.0,0.4,0.0,1.7,2.3,9.9\n")
    cols = {"time": "t", "speed_left": "wl", "speed_right": "wr", "current_left": "il",
            "current_right": "ir", "accel_z": "az"}
    with pytest.raises(InvalidParameterError, match="need track_width_m"):
        read_csv_log(path, cols)
    log = read_csv_log(path, cols, track_width_m=0.5)
    np.testing.assert_allclose(log.v_mps, [0.2, 0.2, 0.2], atol=1e-15)
    np.testing.assert_allclose(log.omega_radps, [0.4, 0.0, -0.8], atol=1e-15)
    assert log.meta.velocity_source == "measured" and log.meta.track_width_m == 0.5


def test_generic_csv_nan_in_drive_row(tmp_path):
    path = tmp_path / "g.csv"
    shutil.copy(GENERIC, path)
    edit_lines(path, lambda ls: [line.replace("200,0.10,20,1200,1300", "200,0.10,,1200,1300") for line in ls])
    with pytest.raises(DataError, match=r"drive stream: column 'omega' has 1 missing .* index 2 \(t=0.2 s\)"):
        read_csv_log(path, GENERIC_COLUMNS, GENERIC_UNITS)
    with pytest.warns(DataRepairWarning, match="interpolated 1 missing value"):
        log = read_csv_log(path, GENERIC_COLUMNS, GENERIC_UNITS, repair=("interpolate_nans",))
    assert log.omega_radps[2] == pytest.approx(np.deg2rad(20))


def write_single_rate(path: Path, n: int = 30, blank: dict[int, tuple[str, ...]] | None = None,
                      right_a: np.ndarray | None = None) -> Path:
    """A single-rate CSV in the default layout (no terrawatt header): row k at t = 0.1 k s;
    ``blank`` maps a row to the columns left empty in it."""
    k = np.arange(n)
    cols = {
        "time_s": 0.1 * k, "v_mps": 0.1 + 0.01 * k, "omega_radps": 0.02 * k, "current_left_a": 2.0 + 0.1 * k,
        "current_right_a": 3.0 + 0.05 * k if right_a is None else right_a, "accel_z_mps2": 9.8 + 0.001 * k,
    }
    lines = [",".join(cols)]
    for i in range(n):
        empty = (blank or {}).get(i, ())
        lines.append(",".join("" if c in empty else repr(float(v[i])) for c, v in cols.items()))
    path.write_text("\n".join(lines) + "\n")
    return path


DRIVE_COLUMNS = ("v_mps", "omega_radps", "current_left_a", "current_right_a")


def test_generic_csv_single_rate_row_without_drive_fields(tmp_path, caplog):
    path = write_single_rate(tmp_path / "s.csv", blank={7: DRIVE_COLUMNS})
    # mixed (default): the row is an IMU-only row, and the split is reported, not silent
    with caplog.at_level(logging.INFO, logger="energy.io"):
        log = read_csv_log(path)
    assert len(log) == 29 and log.accel_time_s.size == 30
    split = "30 row(s) split into 29 drive+IMU, 0 drive-only and 1 IMU-only"
    assert split in log.meta.notes
    assert any(split in r.getMessage() for r in caplog.records)
    # single: every row is a drive sample, the empty fields are NaNs
    with pytest.raises(DataError, match=r"drive stream: column 'current_left' has 1 missing or non-finite "
                                        r"value\(s\), first at index 7 \(t=0\.7"):
        read_csv_log(path, rates="single")
    with pytest.warns(DataRepairWarning, match="interpolated 1 missing value"):
        fixed = read_csv_log(path, rates="single", repair=("interpolate_nans",))
    assert len(fixed) == 30 and "split into" not in fixed.meta.notes
    assert fixed.v_mps[7] == pytest.approx(0.17, abs=1e-12)


def test_generic_csv_single_rate_row_without_accel(tmp_path):
    path = write_single_rate(tmp_path / "s.csv", blank={12: ("accel_z_mps2",)})
    log = read_csv_log(path)
    assert len(log) == 30 and log.accel_time_s.size == 29
    assert "29 drive+IMU, 1 drive-only and 0 IMU-only" in log.meta.notes
    with pytest.raises(DataError, match=r"acceleration stream: column 'accel_z' has 1 missing .* first at index 12"):
        read_csv_log(path, rates="single")
    with pytest.warns(DataRepairWarning, match=r"interpolated 1 missing value\(s\) of column 'accel_z'"):
        fixed = read_csv_log(path, rates="single", repair="interpolate_nans")
    assert fixed.accel_time_s.size == 30 and fixed.accel_z_mps2[12] == pytest.approx(9.812, abs=1e-12)


def test_generic_csv_mixed_rates_reported_and_unknown_rates():
    log = read_csv_log(GENERIC, GENERIC_COLUMNS, GENERIC_UNITS)
    assert "rates='mixed': 51 row(s) split into 11 drive+IMU, 0 drive-only and 40 IMU-only" in log.meta.notes
    with pytest.raises(UnknownNameError, match=r"rates must be one of \('mixed', 'single'\), got 'dual'"):
        read_csv_log(GENERIC, GENERIC_COLUMNS, GENERIC_UNITS, rates="dual")
    # a mixed-rate file read as single-rate: the IMU-only rows are NaNs of the drive stream
    with pytest.raises(DataError, match=r"drive stream: column 'current_left' has 40 missing .* first at index 1"):
        read_csv_log(GENERIC, GENERIC_COLUMNS, GENERIC_UNITS, rates="single")


def test_generic_csv_label_on_row_without_drive_values(tmp_path):
    # a ground label is a drive field: the row is a drive sample with NaNs, not an IMU-only row
    path = tmp_path / "g.csv"
    shutil.copy(GENERIC, path)
    edit_lines(path, lambda ls: [line + "grass" if line == "20,,,,,9.82," else line for line in ls])
    with pytest.raises(DataError, match=r"drive stream: column 'current_left' has 1 missing .* index 1 \(t=0\.02 s\)"):
        read_csv_log(path, GENERIC_COLUMNS, GENERIC_UNITS)


def test_generic_csv_float_milliamps_mostly_idle_declared_as_amps(tmp_path):
    # one side idle (0) in 24 of 30 rows, then float mA: median 0 and not integer-valued
    right = np.where(np.arange(30) < 24, 0.0, 1500.25 + 400.5 * np.arange(30))
    path = write_single_rate(tmp_path / "s.csv", right_a=right)
    with pytest.raises(UnitError, match=r"current_right_a is declared in A but its values look like mA \(median "
                                        r"\|I\| = 0 A, 99th percentile of the non-zero \|I\| = 1\.309e\+04 A.*declare 'mA'"):
        read_csv_log(path, rates="single")
    log = read_csv_log(path, rates="single", units={"current_right": "mA"})
    assert log.current_right_a.max() == pytest.approx(13.11475, abs=1e-12)
    # a ground robot's real peaks (tens of A) still read as A
    write_single_rate(path, right_a=np.where(np.arange(30) < 24, 0.0, 35.5))
    assert read_csv_log(path, rates="single").current_right_a.max() == 35.5


def test_generic_csv_empty_label(tmp_path):
    path = tmp_path / "g.csv"
    shutil.copy(GENERIC, path)
    edit_lines(path, lambda ls: [line.replace(",grass", ",") if line.startswith("300,") else line for line in ls])
    with pytest.raises(DataError, match=r"1 empty ground label\(s\), first at index 3"):
        read_csv_log(path, GENERIC_COLUMNS, GENERIC_UNITS)


def test_write_read_roundtrip_exact(tmp_path):
    rng = np.random.default_rng(7)
    n, m = 40, 333
    t = np.cumsum(rng.uniform(0.09, 0.11, n))
    ta = np.linspace(t[0] - 0.05, t[-1] + 0.05, m) + rng.uniform(-1e-3, 1e-3, m)  # jittered, no gaps
    pose = np.column_stack([rng.normal(size=n), rng.normal(size=n), rng.uniform(-np.pi, np.pi, n)])
    log = InteractionLog(
        t, rng.normal(size=n), rng.normal(size=n), rng.uniform(0, 20, n), rng.uniform(0, 20, n),
        ta, 9.81 + rng.normal(size=m), pose_xyh=pose, ground=rng.choice(["snow", "ice"], n),
        meta=LogMeta(robot="husky", source="synthetic", ground_label="snow", velocity_source="measured",
                     track_width_m=0.6, notes="x", start_time_ns=1_700_000_000_000_000_000),
    )
    path = write_csv_log(log, tmp_path / "sub" / "log.csv")
    assert [p.name for p in path.parent.iterdir()] == ["log.csv"]  # no temp file left behind
    back = read_csv_log(path)
    for name in ("time_s", "v_mps", "omega_radps", "current_left_a", "current_right_a",
                 "accel_time_s", "accel_z_mps2", "pose_xyh", "ground"):
        np.testing.assert_array_equal(getattr(back, name), getattr(log, name), err_msg=name)
    assert back.meta.robot == "husky" and back.meta.ground_label == "snow"
    assert back.meta.velocity_source == "measured" and back.meta.track_width_m == 0.6
    assert back.meta.start_time_ns == log.meta.start_time_ns
    assert back.meta.source == str(path)


def test_write_roundtrip_borealtc_fixture(tmp_path):
    log = read_borealtc(BOREALTC_FIX)[0]
    back = read_csv_log(write_csv_log(log, tmp_path / "a.csv"))
    np.testing.assert_array_equal(back.time_s, log.time_s)
    np.testing.assert_array_equal(back.accel_z_mps2, log.accel_z_mps2)
    np.testing.assert_array_equal(back.omega_radps, log.omega_radps)
    assert back.pose_xyh is None and back.ground is None and back.meta.ground_label == "asphalt"


def test_write_rejects_bad_labels_and_objects(tmp_path):
    log = read_csv_log(GENERIC, GENERIC_COLUMNS, GENERIC_UNITS)
    import dataclasses

    bad = dataclasses.replace(log, ground=["a,b"] * 11)
    with pytest.raises(InvalidParameterError, match=r"ground labels \['a,b'\] cannot be written"):
        write_csv_log(bad, tmp_path / "x.csv")
    with pytest.raises(InvalidParameterError, match="log must be an InteractionLog"):
        write_csv_log({"time_s": []}, tmp_path / "x.csv")
    assert not any(tmp_path.iterdir())


def test_csv_format_version_and_corrupt_header(tmp_path):
    log = read_csv_log(GENERIC, GENERIC_COLUMNS, GENERIC_UNITS)
    path = write_csv_log(log, tmp_path / "v.csv")
    edit_lines(path, lambda ls: [ls[0].replace('"format_version": 1', '"format_version": 2')] + ls[1:])
    with pytest.raises(FormatVersionError, match="format version 2"):
        read_csv_log(path)
    edit_lines(path, lambda ls: ["# terrawatt-log {not json"] + ls[1:])
    with pytest.raises(FileFormatError, match="corrupt terrawatt-log header"):
        read_csv_log(path)


# ============================================================================ ROS bags
try:
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore
except ImportError:  # the 'ros' extra is optional
    HAVE_ROSBAGS = False
else:
    HAVE_ROSBAGS = True
requires_rosbags = pytest.mark.skipif(not HAVE_ROSBAGS, reason="rosbags (the 'ros' extra) is not installed")

BASE_NS = 1_700_000_000_000_000_000
MS = 1_000_000


def bag_content() -> dict:
    """Known streams (integer ns): IMU 100 Hz 0..2 s with header stamps; currents 10 Hz at
    50..1950 ms (receive time only); commands 5 Hz at 300..1100 ms."""
    imu_ns = [BASE_NS + k * 10 * MS for k in range(201)]
    cur_ns = [BASE_NS + (50 + 100 * k) * MS for k in range(20)]
    cmd_ns = [BASE_NS + (300 + 200 * k) * MS for k in range(5)]
    return {
        "imu_ns": imu_ns,
        "az": [9.81 + 0.001 * k for k in range(201)],
        "cur_ns": cur_ns,
        "left": [1.0 + 0.25 * k for k in range(20)],
        "right": [2.0 + 0.5 * k for k in range(20)],
        "cmd_ns": cmd_ns,
        "v": [0.1 * (k + 1) for k in range(5)],
        "w": [-0.2 * k for k in range(5)],
    }


def write_bag(path: Path, kind: str, content: dict, multiarray: bool = False, odom: bool = False,
              scale: float = 1.0, imu_stamp_ns: list[int] | None = None, empty_topics: tuple[str, ...] = ()) -> Path:
    """Write ``content`` to a bag. IMU messages are received 1 ms after ``content["imu_ns"]``
    and stamped with ``imu_stamp_ns`` (default: ``content["imu_ns"]``); ``empty_topics`` get
    a connection but no messages."""
    ros1 = kind == "ros1"
    if imu_stamp_ns is None:
        imu_stamp_ns = content["imu_ns"]
    ts = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    T = ts.types
    ser = ts.serialize_ros1 if ros1 else ts.serialize_cdr

    def vec(x=0.0, y=0.0, z=0.0):
        return T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)

    def header(ns):
        stamp = T["builtin_interfaces/msg/Time"](sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
        return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id="base") if ros1 else T["std_msgs/msg/Header"](
            stamp=stamp, frame_id="base")

    if ros1:
        writer = Writer1(path)
    else:
        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        writer = Writer2(path, version=9, storage_plugin=plugin)
    quat = T["geometry_msgs/msg/Quaternion"]
    with writer:
        conns = {}

        def conn(topic, typ):
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, typ, typestore=ts)
            return conns[topic]

        msgs = []
        for ns, stamp_ns, az in zip(content["imu_ns"], imu_stamp_ns, content["az"]):
            m = T["sensor_msgs/msg/Imu"](
                header=header(stamp_ns), orientation=quat(x=0.0, y=0.0, z=0.0, w=1.0), orientation_covariance=np.zeros(9),
                angular_velocity=vec(), angular_velocity_covariance=np.zeros(9),
                linear_acceleration=vec(z=az), linear_acceleration_covariance=np.zeros(9))
            msgs.append((ns + MS, "/imu/data", "sensor_msgs/msg/Imu", m))  # received 1 ms after the stamp
        for ns, left, right in zip(content["cur_ns"], content["left"], content["right"]):
            if multiarray:
                lay = T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
                arr = T["std_msgs/msg/Float64MultiArray"](layout=lay, data=np.array([left, right]) * scale)
                msgs.append((ns, "/drive/current", "std_msgs/msg/Float64MultiArray", arr))
            else:
                msgs.append((ns, "/drive/current_left", "std_msgs/msg/Float64", T["std_msgs/msg/Float64"](data=left * scale)))
                msgs.append((ns, "/drive/current_right", "std_msgs/msg/Float64", T["std_msgs/msg/Float64"](data=right * scale)))
        for i, (ns, v, w) in enumerate(zip(content["cmd_ns"], content["v"], content["w"])):
            twist = T["geometry_msgs/msg/Twist"](linear=vec(x=v), angular=vec(z=w))
            if odom:
                pose = T["geometry_msgs/msg/PoseWithCovariance"](
                    pose=T["geometry_msgs/msg/Pose"](
                        position=T["geometry_msgs/msg/Point"](x=float(i), y=2.0 * i, z=0.0),
                        orientation=quat(x=0.0, y=0.0, z=np.sin(0.1 * i), w=np.cos(0.1 * i))),
                    covariance=np.zeros(36))
                tw = T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=np.zeros(36))
                m = T["nav_msgs/msg/Odometry"](header=header(ns), child_frame_id="base", pose=pose, twist=tw)
                msgs.append((ns, "/odom", "nav_msgs/msg/Odometry", m))
            else:
                msgs.append((ns, "/cmd_vel", "geometry_msgs/msg/Twist", twist))
        for ns, topic, typ, m in sorted(msgs, key=lambda x: x[0]):
            if topic in empty_topics:
                conn(topic, typ)
            else:
                writer.write(conn(topic, typ), ns, ser(m, typ))
    return path


def expected_drive(content: dict, timeout_s: float | None = 0.5) -> dict:
    origin = min(content["imu_ns"][0], content["cur_ns"][0], content["cmd_ns"][0])
    sec = lambda ns: (np.asarray(ns, dtype=np.int64) - origin).astype(np.float64) / 1e9  # noqa: E731
    tc, ti, tv = sec(content["cur_ns"]), sec(content["imu_ns"]), sec(content["cmd_ns"])
    keep = (tc >= max(tc[0], ti[0])) & (tc <= min(tc[-1], ti[-1]))
    td = tc[keep]
    idx = np.searchsorted(tv, td, side="right") - 1
    valid = idx >= 0
    if timeout_s is not None:
        valid &= td - tv[np.maximum(idx, 0)] <= timeout_s
    v = np.where(valid, np.asarray(content["v"])[np.maximum(idx, 0)], 0.0)
    w = np.where(valid, np.asarray(content["w"])[np.maximum(idx, 0)], 0.0)
    return {"time_s": td, "v": v, "w": w, "left": np.asarray(content["left"])[keep],
            "right": np.asarray(content["right"])[keep], "ti": ti, "origin": origin}


@requires_rosbags
@pytest.mark.parametrize("kind", ["ros2", "mcap", "ros1"])
def test_rosbag_roundtrip_exact(tmp_path, kind):
    content = bag_content()
    path = write_bag(tmp_path / ("run.bag" if kind == "ros1" else "run"), kind, content)
    log = read_rosbag(path, "/cmd_vel", "/imu/data", ("/drive/current_left", "/drive/current_right"), robot="jackal",
                      ground_label="grass")
    exp = expected_drive(content)
    np.testing.assert_array_equal(log.time_s, exp["time_s"])
    np.testing.assert_array_equal(log.v_mps, exp["v"])
    np.testing.assert_array_equal(log.omega_radps, exp["w"])
    np.testing.assert_array_equal(log.current_left_a, exp["left"])
    np.testing.assert_array_equal(log.current_right_a, exp["right"])
    # IMU on header stamps (not the 1 ms later receive time), bracketing the drive span
    ia = np.flatnonzero(exp["ti"] <= log.time_s[0])[-1]
    ib = np.flatnonzero(exp["ti"] >= log.time_s[-1])[0]
    np.testing.assert_array_equal(log.accel_time_s, exp["ti"][ia : ib + 1])
    np.testing.assert_array_equal(log.accel_z_mps2, np.asarray(content["az"])[ia : ib + 1])
    assert log.meta.start_time_ns == exp["origin"] == BASE_NS
    assert log.meta.velocity_source == "commanded" and log.meta.robot == "jackal"
    assert "/imu/data: header stamps" in log.meta.notes and "/drive/current_left: receive time" in log.meta.notes
    # commands stop at 1.1 s: zero after the 0.5 s timeout, zero before the first one
    assert log.v_mps[log.time_s < 0.3].tolist() == [0.0] * int(np.sum(log.time_s < 0.3))
    assert np.all(log.v_mps[log.time_s > 1.6] == 0.0)
    assert np.any(log.v_mps > 0)


@requires_rosbags
def test_rosbag_receive_time_and_no_timeout(tmp_path):
    content = bag_content()
    path = write_bag(tmp_path / "run", "ros2", content)
    log = read_rosbag(path, current_topics=("/drive/current_left", "/drive/current_right"),
                      use_header_stamps=False, cmd_vel_timeout_s=None)
    assert "/imu/data: receive time" in log.meta.notes
    # without a timeout the drive stream starts at the first command and the last command is held
    received = dict(content, imu_ns=[ns + MS for ns in content["imu_ns"]])  # IMU receive time = stamp + 1 ms
    exp = expected_drive(received, timeout_s=None)
    assert exp["origin"] == BASE_NS + MS
    keep = exp["time_s"] >= (content["cmd_ns"][0] - exp["origin"]) / 1e9
    np.testing.assert_array_equal(log.time_s, exp["time_s"][keep])
    np.testing.assert_array_equal(log.v_mps, exp["v"][keep])
    assert log.v_mps[-1] == content["v"][-1]


@requires_rosbags
def test_rosbag_multiarray_in_milliamps(tmp_path):
    content = bag_content()
    path = write_bag(tmp_path / "run", "mcap", content, multiarray=True, scale=1000.0)
    with pytest.raises(UnitError, match="declared in A but its values look like mA"):
        read_rosbag(path, current_topics="/drive/current")
    log = read_rosbag(path, current_topics="/drive/current", current_unit="mA")
    exp = expected_drive(content)
    np.testing.assert_allclose(log.current_left_a, exp["left"], rtol=1e-15)
    np.testing.assert_allclose(log.current_right_a, exp["right"], rtol=1e-15)


@requires_rosbags
def test_rosbag_odometry_measured_with_pose(tmp_path):
    content = bag_content()
    path = write_bag(tmp_path / "run.bag", "ros1", content, odom=True)
    log = read_rosbag(path, cmd_vel_topic="/odom", current_topics=("/drive/current_left", "/drive/current_right"))
    assert log.meta.velocity_source == "measured" and log.pose_xyh is not None
    origin = BASE_NS
    tv = (np.asarray(content["cmd_ns"]) - origin) / 1e9
    assert log.time_s[0] >= tv[0] and log.time_s[-1] <= tv[-1]  # inside the odometry span
    np.testing.assert_allclose(log.v_mps, np.interp(log.time_s, tv, content["v"]), atol=1e-12)
    np.testing.assert_allclose(log.pose_xyh[:, 0], np.interp(log.time_s, tv, np.arange(5.0)), atol=1e-12)
    np.testing.assert_allclose(log.pose_xyh[:, 2], np.interp(log.time_s, tv, 0.2 * np.arange(5)), atol=1e-12)


@requires_rosbags
def test_rosbag_bad_inputs(tmp_path):
    content = bag_content()
    path = write_bag(tmp_path / "run", "ros2", content, multiarray=True)
    with pytest.raises(DataError, match=r"topic\(s\) \['/drive/current_left'.* not in the bag"):
        read_rosbag(path)
    with pytest.raises(DataError, match="topic '/imu/data' has type 'sensor_msgs/msg/Imu'; expected one of"):
        read_rosbag(path, cmd_vel_topic="/imu/data", current_topics="/drive/current")
    with pytest.raises(DataError, match="has type 'std_msgs/msg/Float64MultiArray'"):
        read_rosbag(path, current_topics=("/drive/current", "/drive/current"))
    with pytest.raises(FileFormatError, match="does not exist"):
        read_rosbag(tmp_path / "nothing")
    with pytest.raises(UnknownNameError, match="current_unit must be one of"):
        read_rosbag(path, current_topics="/drive/current", current_unit="uA")
    with pytest.raises(InvalidParameterError, match="cmd_vel_timeout_s must be"):
        read_rosbag(path, current_topics="/drive/current", cmd_vel_timeout_s=0)
    not_a_bag = tmp_path / "junk.bag"
    not_a_bag.write_bytes(b"definitely not a bag")
    with pytest.raises(FileFormatError, match="cannot read bag"):
        read_rosbag(not_a_bag)


@requires_rosbags
@pytest.mark.parametrize("shift_s", [-100.0, -0.8, 0.8])
def test_rosbag_header_clock_offset_raises(tmp_path, shift_s):
    content = bag_content()
    shift_ns = round(shift_s * 1e9)
    stamps = [ns + shift_ns for ns in content["imu_ns"]]  # publisher clock off the recorder's
    path = write_bag(tmp_path / "run", "ros2", content, imu_stamp_ns=stamps)
    offset = (MS - shift_ns) / 1e9  # median of receive time - header stamp
    with pytest.raises(DataError, match=rf"topic '/imu/data': median \(receive time - header stamp\) is "
                                        rf"{re.escape(repr(offset))} s, expected within \+/-0\.5 s.*"
                                        r"use_header_stamps=False"):
        read_rosbag(path)
    # on receive time the IMU and the currents share the recorder's clock: same as an unshifted bag
    log = read_rosbag(path, use_header_stamps=False)
    ref = read_rosbag(write_bag(tmp_path / "ref", "ros2", content), use_header_stamps=False)
    np.testing.assert_array_equal(log.accel_time_s, ref.accel_time_s)
    np.testing.assert_array_equal(log.time_s, ref.time_s)
    # a wider tolerance is an explicit choice
    if abs(shift_s) < 1:
        assert read_rosbag(path, max_clock_offset_s=1.0).meta.notes.count("header stamps") == 1
    with pytest.raises(InvalidParameterError, match=r"max_clock_offset_s must be finite, got nan"):
        read_rosbag(path, max_clock_offset_s=float("nan"))


@requires_rosbags
def test_rosbag_notes_clock_offset(tmp_path):
    log = read_rosbag(write_bag(tmp_path / "run", "mcap", bag_content()))
    assert "/imu/data: header stamps (median receive time - stamp 0.001 s)" in log.meta.notes


@requires_rosbags
def test_rosbag_unsorted_header_stamps_raise_then_sort(tmp_path):
    content = bag_content()
    ref = read_rosbag(write_bag(tmp_path / "ref", "ros2", content))
    stamps = list(content["imu_ns"])
    stamps[50], stamps[51] = stamps[51], stamps[50]  # received in order, stamped out of order
    path = write_bag(tmp_path / "run", "ros2", content, imu_stamp_ns=stamps)
    with pytest.raises(DataError, match=r"/imu/data: timestamps are not sorted; 1 step\(s\) go backwards, first at "
                                        r"index 51 .*repair=\('sort',\)"):
        read_rosbag(path)
    with pytest.warns(DataRepairWarning, match=r"/imu/data: sorted timestamps \(1 backward step"):
        log = read_rosbag(path, repair="sort")
    np.testing.assert_array_equal(log.accel_time_s, ref.accel_time_s)
    i = int(np.searchsorted(log.accel_time_s, 0.5))  # stamp index 50 (t = 0.5 s)
    assert (log.accel_z_mps2[i], log.accel_z_mps2[i + 1]) == (content["az"][51], content["az"][50])


@requires_rosbags
def test_rosbag_duplicated_receive_times_raise_then_drop(tmp_path):
    content = bag_content()
    content["cur_ns"][5] = content["cur_ns"][4]
    path = write_bag(tmp_path / "run", "ros2", content)
    with pytest.raises(DataError, match=r"/drive/current_left: 1 duplicated timestamp\(s\), first at index 5 "
                                        r"\(t=0\.45 s\); pass repair=\('drop_duplicates',\)"):
        read_rosbag(path)
    with pytest.warns(DataRepairWarning) as record:
        log = read_rosbag(path, repair="drop_duplicates")
    assert sorted(str(w.message).split(": ", 1)[1] for w in record) == [
        f"/drive/current_{side}: dropped 1 sample(s) with a duplicated timestamp" for side in ("left", "right")
    ]
    assert len(log) == 19 and log.current_left_a[4] == content["left"][4]


@requires_rosbags
def test_rosbag_nan_current_raises_then_interpolates(tmp_path):
    content = bag_content()
    content["left"][3] = float("nan")
    path = write_bag(tmp_path / "run", "mcap", content)
    with pytest.raises(DataError, match=r"/drive/current_left: column 'left' has 1 missing or non-finite value\(s\), "
                                        r"first at index 3 \(t=0\.35 s\); pass repair=\('interpolate_nans',\)"):
        read_rosbag(path)
    with pytest.warns(DataRepairWarning, match=r"interpolated 1 missing value\(s\) of column 'left'"):
        log = read_rosbag(path, repair=("interpolate_nans",))
    assert log.current_left_a[3] == pytest.approx(0.5 * (content["left"][2] + content["left"][4]), abs=1e-12)


@requires_rosbags
@pytest.mark.parametrize("kind", ["ros2", "mcap"])
def test_rosbag_empty_topic(tmp_path, kind):
    path = write_bag(tmp_path / "run", kind, bag_content(), empty_topics=("/drive/current_right",))
    with pytest.raises(DataError, match=r"topic '/drive/current_right' has no messages"):
        read_rosbag(path)


def test_rosbag_without_rosbags_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)  # import of it now fails
    with pytest.raises(OptionalDependencyError, match=r"pip install 'terrawatt\[ros\]'"):
        read_rosbag(tmp_path / "run")


@requires_rosbags
def test_rosbag_multiarray_wrong_length(tmp_path):
    ts = get_typestore(Stores.ROS2_HUMBLE)
    T = ts.types
    path = tmp_path / "bad"
    with Writer2(path, version=9) as w:
        c = w.add_connection("/drive/current", "std_msgs/msg/Float64MultiArray", typestore=ts)
        ci = w.add_connection("/imu/data", "sensor_msgs/msg/Imu", typestore=ts)
        cv = w.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=ts)
        lay = T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
        w.write(c, BASE_NS, ts.serialize_cdr(T["std_msgs/msg/Float64MultiArray"](layout=lay, data=np.ones(3)),
                                             "std_msgs/msg/Float64MultiArray"))
        v3 = T["geometry_msgs/msg/Vector3"]
        w.write(cv, BASE_NS, ts.serialize_cdr(T["geometry_msgs/msg/Twist"](linear=v3(x=0.0, y=0.0, z=0.0),
                                              angular=v3(x=0.0, y=0.0, z=0.0)), "geometry_msgs/msg/Twist"))
        stamp = T["builtin_interfaces/msg/Time"](sec=1, nanosec=0)
        imu = T["sensor_msgs/msg/Imu"](
            header=T["std_msgs/msg/Header"](stamp=stamp, frame_id=""),
            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
            orientation_covariance=np.zeros(9), angular_velocity=v3(x=0.0, y=0.0, z=0.0),
            angular_velocity_covariance=np.zeros(9), linear_acceleration=v3(x=0.0, y=0.0, z=9.8),
            linear_acceleration_covariance=np.zeros(9))
        w.write(ci, BASE_NS, ts.serialize_cdr(imu, "sensor_msgs/msg/Imu"))
    with pytest.raises(DataError, match=r"1 message\(s\) do not hold exactly \[left, right\].*3 value"):
        read_rosbag(path, current_topics="/drive/current")
