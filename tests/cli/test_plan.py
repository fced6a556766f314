"""The ``terrawatt plan`` and ``terrawatt demo`` commands (terrawatt_cli.plan): each end to end on small maps."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from cli_samples import is_png, one_line_error

import terrain
from terrawatt_cli import main


def test_demo_plans_on_the_bundled_map_and_writes_json_and_plot(tmp_path, capsys):
    rc = main(["demo", "--planner", "lattice", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0
    assert "shortest distance" in out and "energy saved vs shortest route" in out
    data = json.loads((tmp_path / "route.json").read_text())
    assert data["status"] == "exact"
    assert set(data["routes"]) == {"min_energy", "lattice", "shortest"}
    saved = data["energy_saved_pct"]
    energies = {k: v["energy_j"] for k, v in data["routes"].items()}
    # the saving printed is the saving between the two routes written
    assert saved == pytest.approx(100.0 * (1 - energies["min_energy"] / energies["shortest"]), rel=1e-9)
    assert saved > 5.0  # the example map is built so that the straight line climbs a hill and crosses sand
    assert data["optimality_ratio"] <= 1.0 + 1e-9  # refined from the heading lattice's optimum, turns in both
    assert data["search_objective"].startswith("drive and turn energy")  # what the lattice's search minimised
    assert is_png(tmp_path / "route.png")


def test_plan_on_a_map_file_goes_around_the_wall(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5",
               "--planner", "lattice", "--out", str(tmp_path / "out")])
    assert rc == 0
    wp = np.array(json.loads((tmp_path / "out" / "route.json").read_text())["routes"]["min_energy"]["waypoints_m"])
    assert wp[:, 1].max() >= 30.0  # through the gap at y in [30, 34)
    assert is_png(tmp_path / "out" / "route.png")
    capsys.readouterr()


def test_plan_stopped_short_by_its_work_bound_is_not_compared_and_fails(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    args = ["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--planner", "RRTstar",
            "--max-evaluations", "30", "--seed", "1", "--out", str(tmp_path / "out")]
    rc = main(args)
    out = capsys.readouterr().out
    data = json.loads((tmp_path / "out" / "route.json").read_text())
    assert rc == 1 and data["status"] == "approximate" and data["max_evaluations"] == 30
    assert "short of the goal" in out and "energy saved" not in out
    assert data["energy_saved_pct"] is None and data["optimality_ratio"] is None
    main(args)  # the same work bound and seed give the same route
    again = json.loads((tmp_path / "out" / "route.json").read_text())
    assert again["routes"]["min_energy"]["waypoints_m"] == data["routes"]["min_energy"]["waypoints_m"]
    capsys.readouterr()


@pytest.mark.parametrize(
    ("start", "message"),
    [(("20.5", "10"), "obstacle"), (("-5", "10"), "outside")],
)
def test_plan_reports_a_bad_start_as_an_error(tmp_path, capsys, wall_map, start, message):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", *start, "--goal", "35", "5", "--planner", "lattice",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    assert message in capsys.readouterr().err


def test_plan_reports_a_corrupt_map_file(tmp_path, capsys):
    bad = tmp_path / "broken.npz"
    bad.write_bytes(b"not a zip archive")
    rc = main(["plan", "--map", str(bad), "--start", "1", "1", "--goal", "2", "2", "--out", str(tmp_path)])
    assert rc == 2
    assert "corrupt" in capsys.readouterr().err


def test_unknown_planner_is_refused_with_the_valid_names(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["demo", "--planner", "Dijkstra", "--out", str(tmp_path)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "Dijkstra" in err and "RRTstar" in err


def test_plan_on_a_geotiff_dem_uses_the_unknown_ground_preset(tmp_path, capsys):
    pytest.importorskip("rasterio", reason="GeoTIFF needs the geo extra (rasterio)")
    from terrain import ramp_map, write_geotiff

    dem = write_geotiff(ramp_map((30, 40), 1.0, grade=0.05), tmp_path / "dem.tif")
    out = tmp_path / "out"
    rc = main(["plan", "--map", str(dem), "--start", "3", "3", "--goal", "36", "26", "--planner", "lattice",
               "--out", str(out)])
    assert rc == 0
    data = json.loads((out / "route.json").read_text())
    assert data["map"] == "dem.tif" and data["status"] == "exact"
    # a DEM carries no ground classes: every cell is unknown and priced as gravel, and says so
    out_text = capsys.readouterr().out
    assert "grounds {}" in out_text and "unknown in 1200 of 1200 cells: priced as 'gravel'" in out_text
    rc = main(["plan", "--map", str(dem), "--start", "3", "3", "--goal", "36", "26", "--planner", "lattice",
               "--unknown-ground", "none", "--out", str(out)])
    assert rc == 2
    assert "unknown" in capsys.readouterr().err


def test_plan_on_a_geotiff_with_nodata_needs_fill_nodata(tmp_path, capsys):
    rasterio = pytest.importorskip("rasterio", reason="GeoTIFF needs the geo extra (rasterio)")
    from affine import Affine

    from terrain import DataRepairWarning

    z = np.tile(0.05 * np.arange(40.0), (30, 1)).astype(np.float32)
    z[10:13, 18:21] = -9999.0  # a hole in the survey
    dem = tmp_path / "holes.tif"
    with rasterio.open(dem, "w", driver="GTiff", height=30, width=40, count=1, dtype="float32",
                       transform=Affine(1.0, 0.0, 0.0, 0.0, -1.0, 30.0), nodata=-9999.0) as dst:
        dst.write(z, 1)
    args = ["plan", "--map", str(dem), "--start", "3", "3", "--goal", "36", "26", "--planner", "lattice",
            "--out", str(tmp_path / "out")]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "--fill-nodata nearest" in err and "fill_nodata=" not in err
    with pytest.warns(DataRepairWarning, match="filled 9 nodata cells"):
        assert main([*args, "--fill-nodata", "nearest"]) == 0
    assert json.loads((tmp_path / "out" / "route.json").read_text())["status"] == "exact"
    capsys.readouterr()


# ---------------------------------------------------------------- CLI rules: exit codes, outputs, flags


def test_plan_with_start_equal_to_goal_says_so(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "5", "5", "--planner", "lattice",
               "--out", str(tmp_path / "out")])
    assert rc == 2
    err = one_line_error(capsys)
    assert "start equals goal" in err and "nan" not in err
    assert not (tmp_path / "out" / "route.json").exists()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--max-slope-deg", "95"], "--max-slope-deg must be between 0 and 90 degrees (exclusive), got 95"),
        (["--unknown-ground", "lava"], "--unknown-ground must be a ground preset"),
        (["--speed", "0"], "--speed must be a number > 0, got 0"),
        (["--time-limit", "-1"], "--time-limit must be a number > 0, got -1"),
        # refused by the library, which names its parameters; the command line says them as its flags
        (["--corridor", "30"], "--corridor applies to coarse-to-fine planning; give --coarse-factor F too"),
        (["--coarse-factor", "4", "--windowed"], "--windowed reads GeoTIFF DEMs (.tif, .tiff), got --map wall.npz"),
    ],
)
def test_plan_flags_are_checked_and_named_as_flags(tmp_path, capsys, wall_map, extra, message):
    path = wall_map.save(tmp_path / "wall.npz")
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--planner", "lattice",
               *extra, "--out", str(tmp_path / "out")])
    assert rc == 2
    err = one_line_error(capsys)
    assert message in err
    assert "max_slope_rad" not in err and "unknown_ground=" not in err and "speed_mps" not in err


def test_unknown_ground_none_on_a_map_with_unknown_cells_names_the_flag(tmp_path, capsys):
    ground = np.zeros((20, 20), dtype=int)
    ground[5:8, 5:8] = -1
    tmap = terrain.TerrainMap(np.zeros((20, 20)), 1.0, ground=ground, ground_names={0: "asphalt"})
    path = tmap.save(tmp_path / "holes.npz")
    rc = main(["plan", "--map", str(path), "--start", "1", "1", "--goal", "18", "18", "--planner", "lattice",
               "--unknown-ground", "none", "--out", str(tmp_path / "out")])
    assert rc == 2
    err = one_line_error(capsys)
    assert "unknown in 9 of 400 cells" in err and "--unknown-ground none" in err and "unknown_ground=" not in err


def test_plan_output_folder_that_is_a_file_is_refused_before_planning(tmp_path, capsys, wall_map, monkeypatch):
    import terrawatt_cli.plan as plan_cli

    path = wall_map.save(tmp_path / "wall.npz")
    out = tmp_path / "out"
    out.write_text("a file where the folder goes")
    monkeypatch.setattr(plan_cli, "plan_and_compare", lambda *a, **k: pytest.fail("planned before checking --out"))
    rc = main(["plan", "--map", str(path), "--start", "5", "5", "--goal", "35", "5", "--planner", "lattice",
               "--out", str(out)])
    assert rc == 2
    assert "--out" in one_line_error(capsys)
    (tmp_path / "out2" / "route.json").mkdir(parents=True)  # the JSON's place taken by a folder
    rc = main(["demo", "--planner", "lattice", "--out", str(tmp_path / "out2")])
    assert rc == 2
    assert "route.json" in one_line_error(capsys)


def test_a_robot_file_plans_as_the_robot_it_holds(tmp_path, capsys):
    # A user's robot: the jackal preset written to a file gives the jackal's route; the same
    # robot 15 kg heavier, edited in the file, costs more on the same map.
    from energy import robot_preset
    from energy.params import write_robot_file

    jackal = robot_preset("jackal")
    write_robot_file(jackal, tmp_path / "mine.json")
    write_robot_file(jackal.replace(mass_kg=jackal.mass_kg + 15.0), tmp_path / "loaded.json")
    energy = {}
    for robot in ("jackal", str(tmp_path / "mine.json"), str(tmp_path / "loaded.json")):
        out = tmp_path / f"out_{len(energy)}"
        assert main(["demo", "--planner", "lattice", "--robot", robot, "--out", str(out)]) == 0
        energy[robot] = json.loads((out / "route.json").read_text())["routes"]["lattice"]["energy_j"]
    assert energy[str(tmp_path / "mine.json")] == energy["jackal"]
    assert energy[str(tmp_path / "loaded.json")] > 1.05 * energy["jackal"]
    capsys.readouterr()
    assert main(["demo", "--robot", str(tmp_path / "absent.json"), "--out", str(tmp_path / "x")]) == 2
    assert "absent.json' is missing" in one_line_error(capsys)
    assert main(["demo", "--robot", "rover", "--out", str(tmp_path / "x")]) == 2
    assert "--robot 'rover' is neither a robot preset" in one_line_error(capsys)


def test_plan_on_the_example_map_is_the_demo(tmp_path, capsys):
    from terrain.procedural import EXAMPLE_GOAL_XY_M, EXAMPLE_START_XY_M

    assert main(["demo", "--planner", "lattice", "--out", str(tmp_path / "demo")]) == 0
    assert main(["plan", "--map", "example", "--start", *map(str, EXAMPLE_START_XY_M), "--goal",
                 *map(str, EXAMPLE_GOAL_XY_M), "--planner", "lattice", "--out", str(tmp_path / "plan")]) == 0
    demo, plan = (json.loads((tmp_path / d / "route.json").read_text()) for d in ("demo", "plan"))
    assert plan["map"] == demo["map"] == "bundled example map"
    assert plan["routes"]["min_energy"]["waypoints_m"] == demo["routes"]["min_energy"]["waypoints_m"]
    capsys.readouterr()


def _plan_args(*extra: str):
    from terrawatt_cli import build_parser

    return build_parser().parse_args(["plan", "--map", "dem.tif", "--start", "1", "1", "--goal", "5", "5",
                                      "--out", "out", *extra])


@pytest.mark.parametrize(
    ("extra", "message"),
    [(["--model", "m.zip", "--coarse-factor", "4"], "--model plans on the whole map with --planner; it does not apply "
                                                     "to --coarse-factor / --windowed yet"),
     (["--windowed"], "--windowed plans coarse-to-fine; give --coarse-factor F too"),
     (["--coarse-factor", "4", "--windowed", "--cell-size", "5"], "--windowed reads the DEM as it is and cannot apply "
      "--cell-size (it needs the whole map): fill or reproject the DEM first (gdal_fillnodata, gdalwarp), or plan "
      "without --windowed"),
     (["--coarse-factor", "4", "--windowed", "--landcover", "lc.tif"], "cannot apply --landcover")],
)
def test_the_coarse_flags_it_cannot_take_are_refused_before_any_work(extra, message):
    from terrawatt_cli.plan import coarse_arg

    with pytest.raises(terrain.InvalidParameterError, match=re.escape(message)):
        coarse_arg(_plan_args(*extra))


def test_the_coarse_flags_make_one_options_value():
    from planner import CoarseOptions
    from terrawatt_cli.plan import coarse_arg

    assert coarse_arg(_plan_args()) is None
    assert coarse_arg(_plan_args("--fill-nodata", "nearest", "--coarse-factor", "4")) == CoarseOptions(factor=4)
    assert coarse_arg(_plan_args("--coarse-factor", "8", "--corridor", "30", "--fine-window-cells", "400")) == \
        CoarseOptions(factor=8, corridor_m=30.0)  # the fine windows' budget applies to a windowed read only
    assert coarse_arg(_plan_args("--coarse-factor", "8", "--windowed", "--fine-window-cells", "400")) == \
        CoarseOptions(factor=8, fine_window_budget_cells=400)
