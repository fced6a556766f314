"""The library names its parameters, the command line its flags: each message that names a library parameter is
printed by the command with the flag that sets it (:func:`terrawatt_cli.error_message`, :func:`terrawatt_cli.common.flag_text`)."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from cli_samples import FIXTURES, one_line_error, patch_map

import terrain
from terrain import ImplausibleDataWarning, InvalidParameterError
from terrawatt_cli import EXIT_BAD_INPUT, PARAMETER_FLAGS, error_message, main
from terrawatt_cli.common import COMMON_FLAGS, flag_text, flagged_warnings

GENERIC = FIXTURES.parent / "generic_ma.csv"


def test_a_message_says_the_parameters_it_names_by_their_flags():
    err = InvalidParameterError("give start or start_lonlat, not both; `model` is a word too", parameter=("start",
                                "start_lonlat", "model"))
    assert error_message(err, {"model": "--model"}) == "give --start or --start-lonlat, not both; --model is a word too"
    # only the parameters the error names, and a marked one only where it is marked
    assert flag_text("start the start", None, PARAMETER_FLAGS) == "start the start"
    assert flag_text("`model` prices like a model", "model", {"model": "--model"}) == "--model prices like a model"
    assert flag_text("`factor` F", "factor", {}) == "`factor` F"  # a command without the flag keeps the mark


def test_a_map_warning_says_the_parameter_it_names_by_its_flag():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with flagged_warnings(COMMON_FLAGS):
            warnings.warn(ImplausibleDataWarning("cells priced as the planner's unknown_ground",
                                                 parameter="unknown_ground"), stacklevel=1)
            warnings.warn("a warning of another kind, as it was", UserWarning, stacklevel=1)
    assert [str(w.message) for w in caught] == ["cells priced as the planner's --unknown-ground",
                                                "a warning of another kind, as it was"]
    assert [w.category for w in caught] == [ImplausibleDataWarning, UserWarning]


def test_plan_says_the_ros_outputs_by_their_flags(tmp_path, capsys):
    rc = main(["plan", "--map", str(patch_map(tmp_path)), "--start", "3", "12", "--goal", "57", "12",
               "--map-frame-origin", "1", "2", "--out", str(tmp_path / "o")])
    assert rc == EXIT_BAD_INPUT
    assert one_line_error(capsys) == ("terrawatt: error: --map-frame-origin applies to --ros2-out and --nav2-map; give "
                                      "one of them\n")


@pytest.mark.parametrize("command, flags", [
    ("reach", ["--battery-ah", "5"]),
    ("tour", ["--sites", "sites.csv", "--battery-ah", "5"]),
])
def test_a_bad_depot_is_said_by_its_flag(tmp_path, capsys, command, flags):
    rc = main([command, "--map", str(patch_map(tmp_path)), "--depot", "nan", "5", *flags, "--out", str(tmp_path / "o")])
    assert rc == EXIT_BAD_INPUT
    assert one_line_error(capsys).startswith("terrawatt: error: --depot must be two finite coordinates (m), got [nan, ")


def test_plan_summary_says_the_unknown_ground_setting_by_its_flag(tmp_path, capsys):
    path = terrain.TerrainMap(np.zeros((12, 30)), 1.0).save(tmp_path / "bare.npz")  # no ground classes: all unknown
    rc = main(["plan", "--map", str(path), "--start", "2", "6", "--goal", "27", "6", "--out", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert rc == 0 and "ground class unknown in 360 of 360 cells" in out
    assert "(--unknown-ground NAME to choose, None / 'none' to refuse them)" in out and "unknown_ground" not in out


def test_a_dem_over_the_memory_budget_names_the_coarse_factor(tmp_path, capsys, monkeypatch):
    pytest.importorskip("rasterio")
    tmap = terrain.TerrainMap(np.zeros((40, 40)), 1.0, (500000.0, 4982900.0), crs="EPSG:32633")
    path = terrain.write_geotiff(tmap, tmp_path / "dem.tif")
    monkeypatch.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", "20000")  # 40 x 40 cells read whole need ~27 kB
    rc = main(["plan", "--map", str(path), "--start", "500002", "4982902", "--goal", "500030", "4982930",
               "--out", str(tmp_path / "o")])
    assert rc == EXIT_BAD_INPUT
    err = one_line_error(capsys)
    assert ("read it by windows: terrain.iter_surface_windows, or plan coarse-to-fine by windows (planner."
            "plan_coarse_to_fine on the file's path, a coarse --coarse-factor F), or raise the budget") in err, err


def test_a_csv_log_of_another_layout_is_said_with_the_csv_flags(tmp_path, capsys):
    rc = main(["train", "--model", "constant", "--data", str(GENERIC), "--out", str(tmp_path / "m.zip")])
    assert rc == EXIT_BAD_INPUT
    err = one_line_error(capsys)
    assert err.rstrip().endswith("map the fields to your columns and declare their units: --csv-columns "
                                 "(time=COLUMN v=COLUMN ...) and --csv-units (time=ms ...) of the CSV layout"), err


def test_csv_flags_for_a_borealtc_folder_are_said_by_their_flags(tmp_path, capsys):
    rc = main(["train", "--model", "constant", "--data", str(FIXTURES), "--csv-rates", "single",
               "--out", str(tmp_path / "m.zip")])
    assert rc == EXIT_BAD_INPUT
    assert re.match(r"terrawatt: error: --csv-columns / --csv-units / --csv-rates / --track-width applies to CSV logs "
                    r"only, and --data '.*borealtc' is read as a BorealTC folder .*give no CSV layout for them "
                    r"\(got rates='single'\)$", one_line_error(capsys).rstrip())
