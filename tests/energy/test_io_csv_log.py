"""Tests of energy.io.csv_log: the generic CSV layout (reader, writer); its header line is in test_io_csv_header.py."""

from __future__ import annotations

import logging
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
from energy_io_samples import (
    BOREALTC_FIX,
    FUZZ_WRITTEN,
    GENERIC,
    GENERIC_COLUMNS,
    GENERIC_UNITS,
    edit_lines,
    fuzz_settings,
    mutate_bytes,
)
from hypothesis import given
from hypothesis import strategies as st

from energy import (
    InteractionLog,
    LogMeta,
    read_borealtc,
    read_csv_log,
    write_csv_log,
)
from energy.io import CsvLayout, LogCleaning
from terrain import (
    DataError,
    DataRepairWarning,
    InvalidParameterError,
    TerrawattError,
    UnitError,
    UnknownNameError,
)


# ========================================================================= generic CSV
def test_generic_csv_units_and_mixed_rates():
    log = read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS), robot="rover")
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
        read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, units))


def test_generic_csv_amps_declared_as_milliamps(tmp_path):
    log = read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS))
    path = write_csv_log(dataclass_replace_currents(log, 0.001), tmp_path / "small.csv")
    # the exported file is in A; declaring mA makes the peak 2 mA, which looks like A
    with pytest.raises(UnitError, match="declared in mA but its peak is .* look like A"):
        read_csv_log(path, CsvLayout(units={"current_left": "mA", "current_right": "mA"}))


def dataclass_replace_currents(log: InteractionLog, scale: float) -> InteractionLog:
    import dataclasses

    return dataclasses.replace(
        log, current_left_a=log.current_left_a * scale, current_right_a=log.current_right_a * scale
    )


def test_generic_csv_deg_per_s_declared_as_rad_per_s():
    units = {k: v for k, v in GENERIC_UNITS.items() if k != "omega"}
    with pytest.raises(UnitError, match=r"\|cmd_w\| reaches 100 rad/s \(index 10\).*declared 'rad/s' looks like deg/s"):
        read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, units))


def test_generic_csv_accel_declared_in_g():
    with pytest.raises(UnitError, match=r"median \|acc_z\| is .* m/s\^2"):
        read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, {**GENERIC_UNITS, "accel_z": "g"}))


def test_generic_csv_bad_maps():
    with pytest.raises(UnknownNameError, match=r"unknown field\(s\) \['speed'\]"):
        read_csv_log(GENERIC, CsvLayout({**GENERIC_COLUMNS, "speed": "cmd_v"}, GENERIC_UNITS))
    with pytest.raises(UnknownNameError, match="unit 'furlong/s' is not known for field 'v'"):
        read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, {**GENERIC_UNITS, "v": "furlong/s"}))
    with pytest.raises(UnknownNameError, match="units given for field"):
        read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, {**GENERIC_UNITS, "x": "m"}))
    cols = {k: v for k, v in GENERIC_COLUMNS.items() if k != "current_right"}
    with pytest.raises(InvalidParameterError, match=r"lacks required field\(s\) \['current_right'\]"):
        read_csv_log(GENERIC, CsvLayout(cols, {k: v for k, v in GENERIC_UNITS.items() if k != "current_right"}))
    with pytest.raises(DataError, match=r"missing column\(s\) \['nope'\]"):
        read_csv_log(GENERIC, CsvLayout({**GENERIC_COLUMNS, "accel_z": "nope"}, GENERIC_UNITS))
    with pytest.raises(InvalidParameterError, match="all of x, y, heading or none"):
        read_csv_log(GENERIC, CsvLayout({**GENERIC_COLUMNS, "x": "pose_x"}, GENERIC_UNITS))


def test_generic_csv_wheel_speeds(tmp_path):
    path = tmp_path / "wheels.csv"
    path.write_text("t,wl,wr,il,ir,az\n0,0.1,0.3,1.5,2.5,9.8\n0.5,0.2,0.2,1.6,2.4,9.7\n1.0,0.4,0.0,1.7,2.3,9.9\n")
    cols = {"time": "t", "speed_left": "wl", "speed_right": "wr", "current_left": "il",
            "current_right": "ir", "accel_z": "az"}
    with pytest.raises(InvalidParameterError, match="need track_width_m"):
        read_csv_log(path, CsvLayout(cols))
    log = read_csv_log(path, CsvLayout(cols, track_width_m=0.5))
    np.testing.assert_allclose(log.v_mps, [0.2, 0.2, 0.2], atol=1e-15)
    np.testing.assert_allclose(log.omega_radps, [0.4, 0.0, -0.8], atol=1e-15)
    assert log.meta.velocity_source == "measured" and log.meta.track_width_m == 0.5


def test_generic_csv_nan_in_drive_row(tmp_path):
    path = tmp_path / "g.csv"
    shutil.copy(GENERIC, path)
    edit_lines(path, lambda ls: [line.replace("200,0.10,20,1200,1300", "200,0.10,,1200,1300") for line in ls])
    with pytest.raises(DataError, match=r"drive stream: column 'omega' has 1 missing .* index 2 \(t=0.2 s\)"):
        read_csv_log(path, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS))
    with pytest.warns(DataRepairWarning, match="interpolated 1 missing value"):
        log = read_csv_log(path, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS),
                           cleaning=LogCleaning(repair=("interpolate_nans",)))
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
        read_csv_log(path, CsvLayout(rates="single"))
    with pytest.warns(DataRepairWarning, match="interpolated 1 missing value"):
        fixed = read_csv_log(path, CsvLayout(rates="single"), cleaning=LogCleaning(repair=("interpolate_nans",)))
    assert len(fixed) == 30 and "split into" not in fixed.meta.notes
    assert fixed.v_mps[7] == pytest.approx(0.17, abs=1e-12)


def test_generic_csv_single_rate_row_without_accel(tmp_path):
    path = write_single_rate(tmp_path / "s.csv", blank={12: ("accel_z_mps2",)})
    log = read_csv_log(path)
    assert len(log) == 30 and log.accel_time_s.size == 29
    assert "29 drive+IMU, 1 drive-only and 0 IMU-only" in log.meta.notes
    with pytest.raises(DataError, match=r"acceleration stream: column 'accel_z' has 1 missing .* first at index 12"):
        read_csv_log(path, CsvLayout(rates="single"))
    with pytest.warns(DataRepairWarning, match=r"interpolated 1 missing value\(s\) of column 'accel_z'"):
        fixed = read_csv_log(path, CsvLayout(rates="single"), cleaning=LogCleaning(repair="interpolate_nans"))
    assert fixed.accel_time_s.size == 30 and fixed.accel_z_mps2[12] == pytest.approx(9.812, abs=1e-12)


def test_generic_csv_mixed_rates_reported_and_unknown_rates():
    log = read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS))
    assert "rates='mixed': 51 row(s) split into 11 drive+IMU, 0 drive-only and 40 IMU-only" in log.meta.notes
    with pytest.raises(UnknownNameError, match=r"rates must be one of \('mixed', 'single'\), got 'dual'"):
        read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS, rates="dual"))
    # a mixed-rate file read as single-rate: the IMU-only rows are NaNs of the drive stream
    with pytest.raises(DataError, match=r"drive stream: column 'current_left' has 40 missing .* first at index 1"):
        read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS, rates="single"))


def test_generic_csv_label_on_row_without_drive_values(tmp_path):
    # a ground label is a drive field: the row is a drive sample with NaNs, not an IMU-only row
    path = tmp_path / "g.csv"
    shutil.copy(GENERIC, path)
    edit_lines(path, lambda ls: [line + "grass" if line == "20,,,,,9.82," else line for line in ls])
    with pytest.raises(DataError, match=r"drive stream: column 'current_left' has 1 missing .* index 1 \(t=0\.02 s\)"):
        read_csv_log(path, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS))


def test_generic_csv_float_milliamps_mostly_idle_declared_as_amps(tmp_path):
    # one side idle (0) in 24 of 30 rows, then float mA: median 0 and not integer-valued
    right = np.where(np.arange(30) < 24, 0.0, 1500.25 + 400.5 * np.arange(30))
    path = write_single_rate(tmp_path / "s.csv", right_a=right)
    with pytest.raises(UnitError, match=r"current_right_a is declared in A but its values look like mA \(median "
                                        r"\|I\| = 0 A, 99th percentile of the non-zero \|I\| = 1\.309e\+04 A.*declare 'mA'"):
        read_csv_log(path, CsvLayout(rates="single"))
    log = read_csv_log(path, CsvLayout(rates="single", units={"current_right": "mA"}))
    assert log.current_right_a.max() == pytest.approx(13.11475, abs=1e-12)
    # a ground robot's real peaks (tens of A) still read as A
    write_single_rate(path, right_a=np.where(np.arange(30) < 24, 0.0, 35.5))
    assert read_csv_log(path, CsvLayout(rates="single")).current_right_a.max() == 35.5


def test_generic_csv_empty_label(tmp_path):
    path = tmp_path / "g.csv"
    shutil.copy(GENERIC, path)
    edit_lines(path, lambda ls: [line.replace(",grass", ",") if line.startswith("300,") else line for line in ls])
    with pytest.raises(DataError, match=r"1 empty ground label\(s\), first at index 3"):
        read_csv_log(path, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS))


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
    log = read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, GENERIC_UNITS))
    import dataclasses

    bad = dataclasses.replace(log, ground=["a,b"] * 11)
    with pytest.raises(InvalidParameterError, match=r"ground labels \['a,b'\] cannot be written"):
        write_csv_log(bad, tmp_path / "x.csv")
    with pytest.raises(InvalidParameterError, match="log must be an InteractionLog"):
        write_csv_log({"time_s": []}, tmp_path / "x.csv")
    assert not any(tmp_path.iterdir())


# ===================================================================== hostile input
def test_csv_times_in_ms_declared_as_s_are_a_unit_error():
    units = dict(GENERIC_UNITS, time="s")  # the fixture's stamps are ms
    with pytest.raises(UnitError, match=r"generic_ma\.csv: drive stream: median rate 0\.01 Hz is below the plausible 0.5 Hz "
                                        r".*the time unit looks wrong"):
        read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, units))
    unchecked = read_csv_log(GENERIC, CsvLayout(GENERIC_COLUMNS, units), cleaning=LogCleaning(check_units=False))
    assert unchecked.drive_rate_hz == pytest.approx(0.01)


def test_csv_columns_must_name_columns():
    with pytest.raises(InvalidParameterError, match="columns must map fields to non-empty column names"):
        read_csv_log(GENERIC, CsvLayout(dict(GENERIC_COLUMNS, accel_z=3), GENERIC_UNITS))


def _read_quietly(path: Path, layout: dict | None = None, cleaning: dict | None = None) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataRepairWarning)
        try:
            read_csv_log(path, CsvLayout(**(layout or {})), cleaning=LogCleaning(**(cleaning or {})))
        except TerrawattError:
            pass


EDITS = st.lists(st.tuples(st.integers(0, 2), st.integers(0, 2**31), st.integers(0, 255)), min_size=1, max_size=8)
CSVISH = st.sampled_from(list(b"0123456789.,-+eE \n\r#\"naimAsv_{}[]:"))


@fuzz_settings(80)
@given(edits=EDITS, truncate=st.one_of(st.none(), st.integers(0, 3000)), which=st.sampled_from(["fixture", "written"]))
def test_fuzz_csv_mutated_files(tmp_path, edits, truncate, which):
    """Mutated generic CSV logs (the fixture, a written log) read or raise a TerrawattError.

    Long run: ``TERRAWATT_FUZZ_EXAMPLES=20 python -m pytest -q tests/energy -k fuzz``.
    """
    if which == "fixture":
        source, kwargs = GENERIC, dict(columns=GENERIC_COLUMNS, units=GENERIC_UNITS)
    else:
        source, kwargs = FUZZ_WRITTEN, {}
    data = mutate_bytes(source.read_bytes(), edits)
    path = tmp_path / "fuzz.csv"
    path.write_bytes(data if truncate is None else data[:truncate])
    _read_quietly(path, kwargs, {})
    _read_quietly(path, {"rates": "single", **kwargs}, {"repair": ("sort", "drop_duplicates", "interpolate_nans"),
                                                        "allow_gaps": True})


@fuzz_settings(60)
@given(data=st.one_of(st.binary(max_size=500), st.lists(CSVISH, max_size=500).map(bytes)))
def test_fuzz_csv_random_bytes(tmp_path, data):
    """Random bytes, alone or under the default header, read or raise a TerrawattError.

    Long run: ``TERRAWATT_FUZZ_EXAMPLES=20 python -m pytest -q tests/energy -k fuzz``.
    """
    path = tmp_path / "fuzz.csv"
    path.write_bytes(data)
    _read_quietly(path)
    path.write_bytes(b"time_s,v_mps,omega_radps,current_left_a,current_right_a,accel_z_mps2\n" + data)
    _read_quietly(path, cleaning={"check_units": False})


def test_an_imu_column_in_g_is_refused_until_its_unit_is_declared(tmp_path):
    t = np.arange(0.0, 4.0, 0.1)
    ta = np.arange(0.0, 3.95, 0.01)
    az_g = 1.0 + 0.02 * np.sin(ta * 40.0)  # an IMU publishing in g, gravity included
    log = InteractionLog(t, np.full(t.size, 0.4), np.zeros(t.size), np.full(t.size, 2.0), np.full(t.size, 2.1),
                         ta, az_g, meta=LogMeta(source="g.csv"))
    path = write_csv_log(log, tmp_path / "g.csv")
    with pytest.raises(UnitError, match=r"looks like an acceleration in g.*units=\{'accel_z': 'g'\}"):
        read_csv_log(path)
    fixed = read_csv_log(path, CsvLayout(units={"accel_z": "g"}))
    np.testing.assert_allclose(fixed.accel_z_mps2, az_g * 9.80665)
    assert not fixed.meta.gravity_removed
    unchecked = read_csv_log(path, cleaning=LogCleaning(check_units=False))
    assert unchecked.meta.gravity_removed  # the user said: no unit checks
