"""Tests of terrawatt_cli.data: the ``--data`` and bag options read logs; the ``--band LO HI`` option and its check."""

from __future__ import annotations

import argparse
import re

import pytest
from cli_samples import FIXTURES, one_line_error

from energy.io import CsvLayout
from terrain import InvalidParameterError
from terrawatt_base.errors import TerrawattError
from terrawatt_cli import EXIT_BAD_INPUT, error_message, main
from terrawatt_cli.data import add_band_option, add_data_options, band_from_args, logs_from_args


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_data_options(parser)
    return parser.parse_args(list(argv))


def test_a_borealtc_folder_gives_logs_with_their_grounds():
    logs = logs_from_args(_parse("--data", str(FIXTURES)), require_currents=True)
    assert {log.meta.ground_label.lower() for log in logs} == {"asphalt", "snow"}


def test_bag_flags_have_their_defaults():
    args = _parse("--data", "x")
    assert args.current_unit == "A" and args.current_fields is None and args.ground_label is None


def test_a_missing_data_path_names_the_flag(tmp_path):
    with pytest.raises(TerrawattError, match="--data"):
        logs_from_args(_parse("--data", str(tmp_path / "nowhere")), require_currents=False)


def _parse_band(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_band_option(parser)
    return parser.parse_args(list(argv))


def test_a_band_is_two_frequencies_and_none_without_the_flag():
    assert band_from_args(_parse_band("--band", "1", "20")) == (1.0, 20.0)
    assert band_from_args(_parse_band()) is None


@pytest.mark.parametrize("band", [("20", "1"), ("-1", "5"), ("0", "inf"), ("nan", "5")])
def test_a_bad_band_is_refused_naming_the_flag(band):
    with pytest.raises(InvalidParameterError, match="--band"):
        band_from_args(_parse_band("--band", *band))


def test_csv_flags_read_csv_logs_of_another_layout(tmp_path):
    from energy import read_csv_log

    generic = FIXTURES.parent / "generic_ma.csv"
    args = _parse("--data", str(generic), "--csv-columns", "time=stamp_ms", "v=cmd_v", "omega=cmd_w",
                  "current_left=left_mA", "current_right=right_mA", "accel_z=acc_z", "ground=label",
                  "--csv-units", "time=ms", "current_left=mA", "current_right=mA", "omega=deg/s")
    (log,) = logs_from_args(args, require_currents=True)
    same = read_csv_log(generic, CsvLayout(dict(args.csv_columns), dict(args.csv_units)))
    assert log.current_right_a.tolist() == same.current_right_a.tolist() and log.time_s[-1] == same.time_s[-1]


@pytest.mark.parametrize(("argv", "match"), [
    (["--csv-columns", "time"], "--csv-columns takes FIELD=VALUE words, each field once; got 'time'"),
    (["--csv-columns", "time=a", "time=b"], "each field once; got 'time=b'"),
    (["--csv-units", "=ms"], "--csv-units takes FIELD=VALUE words"),
    (["--track-width", "0"], "--track-width must be a number > 0, got 0"),
])
def test_bad_csv_words_fail_while_parsing_naming_the_flag(argv, match):
    with pytest.raises(TerrawattError, match=match):
        _parse("--data", "x", *argv)


def test_a_bad_csv_map_names_the_flags(tmp_path):
    args = _parse("--data", str(FIXTURES), "--csv-columns", "tim=stamp_ms")
    with pytest.raises(TerrawattError, match=r"--csv-columns / --csv-units: columns has unknown field\(s\) \['tim'\]"):
        logs_from_args(args, require_currents=True)


def test_csv_flags_for_a_borealtc_folder_are_refused_naming_them():
    args = _parse("--data", str(FIXTURES), "--csv-columns", "time=stamp_ms", "v=cmd_v", "omega=cmd_w", "accel_z=az")
    with pytest.raises(InvalidParameterError, match=r"applies to CSV logs only, and --data '.*borealtc' is read as a "
                                                    r"BorealTC folder"):
        logs_from_args(args, require_currents=True)


def test_a_track_width_with_v_and_omega_columns_is_refused_naming_it():
    generic = FIXTURES.parent / "generic_ma.csv"
    args = _parse("--data", str(generic), "--csv-columns", "time=stamp_ms", "v=cmd_v", "omega=cmd_w",
                  "current_left=left_mA", "current_right=right_mA", "accel_z=acc_z", "--track-width", "0.55")
    with pytest.raises(InvalidParameterError, match=r"^track_width_m 0\.55 derives omega from wheel "
                                                    r"speeds .*the layout's velocities are v and omega") as raised:
        logs_from_args(args, require_currents=True)
    assert re.match(r"--track-width 0\.55 derives omega .*map the wheel speeds instead \(--csv-columns speed_left=COLUMN "
                    r"speed_right=COLUMN\)$", error_message(raised.value))  # said by the flags


@pytest.mark.parametrize("flags", [["--data", "BOREALTC", "--csv-rates", "single"],
                                   ["--data", "BOREALTC", "--track-width", "0.5"],
                                   ["--data", "GENERIC", "--csv-columns", "time=stamp_ms", "v=cmd_v", "omega=cmd_w",
                                    "current_left=left_mA", "current_right=right_mA", "accel_z=acc_z",
                                    "--csv-units", "time=ms", "--track-width", "0.55"]])
def test_ignored_csv_flags_exit_2_with_one_line(tmp_path, capsys, flags):
    paths = {"BOREALTC": str(FIXTURES), "GENERIC": str(FIXTURES.parent / "generic_ma.csv")}
    rc = main(["train", "--model", "physics", *[paths.get(f, f) for f in flags], "--out", str(tmp_path / "m")])
    assert rc == EXIT_BAD_INPUT
    assert "--track-width" in one_line_error(capsys) and not (tmp_path / "m").exists()  # the `csv` layout, by its flags


def test_the_path_the_library_names_is_said_as_the_flag_that_gave_it(tmp_path):
    from terrain import DataError

    args = _parse("--data", str(tmp_path / "missing"))
    with pytest.raises(DataError, match=r"^--data '.*missing' does not exist"):
        logs_from_args(args, require_currents=False)
    args.calibration_data = tmp_path / "gone"
    with pytest.raises(DataError, match=r"^--calibration-data '.*gone' does not exist"):
        logs_from_args(args, require_currents=False, flag="--calibration-data")
