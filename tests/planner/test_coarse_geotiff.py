"""Coarse-to-fine planning straight from a GeoTIFF read by windows equals planning on the whole map."""

from __future__ import annotations

import json

import numpy as np
import pytest

from planner import CoarseOptions, plan_coarse_to_fine
from planner.coarse import downsample_cost
from planner.cost_spec import CostSpec
from terrain import (
    FileFormatError,
    InvalidParameterError,
    NodataError,
    procedural_map,
    read_geotiff,
    write_geotiff,
)
from terrawatt_base.errors import BlockedPositionError, OutOfBoundsError

rasterio = pytest.importorskip("rasterio", reason="GeoTIFF support needs the geo extra (rasterio)")

START, GOAL = (5.5, 6.5), (90.5, 120.5)


@pytest.fixture(scope="module")
def dem_path(tmp_path_factory):
    tmap = procedural_map((131, 97), 1.0, seed=4, origin_xy_m=(0.0, 0.0))
    tmap.crs = "EPSG:32633"
    return write_geotiff(tmap, tmp_path_factory.mktemp("dem") / "dem.tif")


def write_dem(path, z, *, origin=(0.0, 0.0), cell=1.0, nodata=None):
    """A north-up float32 DEM whose map row 0 is ``z[0]`` (the southern edge)."""
    rows, cols = z.shape
    transform = rasterio.Affine(cell, 0.0, origin[0], 0.0, -cell, origin[1] + rows * cell)
    with rasterio.open(path, "w", driver="GTiff", height=rows, width=cols, count=1, dtype="float32",
                       crs="EPSG:32633", transform=transform, nodata=nodata) as dst:
        dst.write(np.asarray(z, "float32")[::-1], 1)
    return path


def ridge_dem(path, gap_rows=(50, 60)):
    """Flat ground with a steep ridge along column 32 (blocked) but for a gap of rows ``gap_rows``."""
    z = np.zeros((64, 64))
    z[:, 32] = 10.0
    z[gap_rows[0]:gap_rows[1], 32] = 0.0
    return write_dem(path, z)


def assert_same_plan(windowed, whole, *, rel=0.0):
    assert windowed.route.status == whole.route.status
    assert windowed.fallback == whole.fallback and windowed.corridor_m == whole.corridor_m
    assert windowed.corridor_cells == whole.corridor_cells
    assert np.array_equal(windowed.coarse_waypoints_m, whole.coarse_waypoints_m)
    if not whole.route.found:
        return
    if rel == 0.0:
        assert np.array_equal(windowed.route.waypoints_m, whole.route.waypoints_m)
        assert np.array_equal(windowed.route.segment_energy_j, whole.route.segment_energy_j)
        assert windowed.route.energy_j == whole.route.energy_j
        assert windowed.objective_j == whole.objective_j
        assert windowed.route.duration_s == whole.route.duration_s
    else:
        np.testing.assert_allclose(windowed.route.waypoints_m, whole.route.waypoints_m, rtol=rel)
        assert windowed.route.energy_j == pytest.approx(whole.route.energy_j, rel=rel)
        assert windowed.objective_j == pytest.approx(whole.objective_j, rel=rel)


@pytest.mark.parametrize(("factor", "window_cells"), [(4, 8), (4, 36), (4, None), (3, 9), (5, 25), (2, 1000)])
def test_windowed_plan_equals_the_whole_map_plan_exactly(dem_path, factor, window_cells):
    whole = plan_coarse_to_fine(CostSpec().build(read_geotiff(dem_path)), START, GOAL,
                                CoarseOptions(factor=factor))
    windowed = plan_coarse_to_fine(dem_path, START, GOAL, CoarseOptions(factor=factor, window_cells=window_cells))
    assert whole.route.status == "exact"
    assert_same_plan(windowed, whole)
    assert windowed.route.planner == "coarse-to-fine" and np.isnan(windowed.optimum_j)
    assert 0 < windowed.fine_window_cells <= 131 * 97 and whole.fine_window_cells == 0


def test_the_coarse_map_from_tiles_equals_downsample_cost(dem_path, tmp_path):
    coarse_whole = downsample_cost(CostSpec().build(read_geotiff(dem_path)), 5)  # 131 x 97: partial blocks
    coarse = plan_coarse_to_fine(dem_path, START, GOAL, CoarseOptions(factor=5, window_cells=10)).coarse_map
    assert np.array_equal(coarse.elevation_m, coarse_whole.terrain.elevation_m)
    assert np.array_equal(coarse.obstacle, coarse_whole.blocked)
    assert coarse.grid == coarse_whole.terrain.grid and coarse.crs == "EPSG:32633"
    # a steep band (45 degrees) of blocked cells, cut by tiles of 9 cells
    z = np.clip(np.arange(50.0) - 20.0, 0.0, 17.0)[None, :].repeat(40, axis=0)
    path = write_dem(tmp_path / "band.tif", z)
    coarse_whole = downsample_cost(CostSpec().build(read_geotiff(path)), 3)
    coarse = plan_coarse_to_fine(path, (2.5, 2.5), (10.5, 30.5), CoarseOptions(factor=3, window_cells=9)).coarse_map
    assert coarse_whole.blocked.any() and np.array_equal(coarse.obstacle, coarse_whole.blocked)
    assert np.array_equal(coarse.elevation_m, coarse_whole.terrain.elevation_m)


def test_a_short_route_reads_a_small_window_in_map_coordinates(dem_path):
    plan = plan_coarse_to_fine(dem_path, (40.5, 60.5), (60.5, 70.5), CoarseOptions(factor=4))
    assert plan.route.status == "exact"
    assert plan.fine_window_cells < 0.3 * 131 * 97
    fine = plan.fine_map
    xmin, ymin, xmax, ymax = fine.bounds
    assert 0 < xmin <= 40.5 and 0 < ymin <= 60.5 and 60.5 <= xmax < 97 and 70.5 <= ymax < 131
    assert np.allclose(plan.route.waypoints_m[[0, -1]], [[40.5, 60.5], [60.5, 70.5]])
    assert plan.coarse_map.shape == (33, 25)


def test_an_origin_that_is_not_a_binary_fraction_agrees_to_rounding(tmp_path):
    z = read_geotiff(write_geotiff(procedural_map((60, 70), 1.0, seed=8), tmp_path / "a.tif")).elevation_m
    path = write_dem(tmp_path / "dem.tif", z, origin=(500_000.3, 4_990_000.7), cell=0.7)
    start, goal = (500_000.3 + 3.1, 4_990_000.7 + 2.9), (500_000.3 + 44.0, 4_990_000.7 + 38.2)
    whole = plan_coarse_to_fine(CostSpec().build(read_geotiff(path)), start, goal, CoarseOptions(factor=4))
    windowed = plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=4, window_cells=16))
    assert whole.route.status == "exact"
    assert_same_plan(windowed, whole, rel=1e-9)


@pytest.mark.parametrize(("gap", "fallbacks"), [((50, 60), {"wider corridor", "whole map"}), ((0, 0), {"whole map"})])
def test_fallbacks_read_bigger_windows_and_equal_the_whole_map(tmp_path, gap, fallbacks):
    path = ridge_dem(tmp_path / "ridge.tif", gap)
    start, goal = (4.5, 4.5), (60.5, 4.5)
    whole = plan_coarse_to_fine(CostSpec().build(read_geotiff(path)), start, goal,
                                CoarseOptions(factor=8, corridor_m=2.0))
    windowed = plan_coarse_to_fine(path, start, goal, CoarseOptions(factor=8, corridor_m=2.0, window_cells=16))
    assert windowed.fallback in fallbacks
    assert_same_plan(windowed, whole)
    if gap == (0, 0):
        assert windowed.route.status == "infeasible"
    else:
        assert windowed.route.status == "exact" and windowed.route.waypoints_m[:, 1].max() >= 50.0
        assert windowed.fine_window_cells > windowed.fine_map.shape[0] * windowed.fine_map.shape[1] / 2


def test_cost_from_prices_every_window_alike(dem_path):
    cost_from = CostSpec(robot="jackal", speed_mps=0.8, unknown_ground="grass")
    whole = plan_coarse_to_fine(cost_from.build(read_geotiff(dem_path)), START, GOAL, CoarseOptions(factor=4))
    windowed = plan_coarse_to_fine(dem_path, START, GOAL, CoarseOptions(factor=4), cost_from=cost_from)
    assert_same_plan(windowed, whole)
    default = plan_coarse_to_fine(dem_path, START, GOAL, CoarseOptions(factor=4))
    assert default.route.energy_j != windowed.route.energy_j


def test_cost_from_that_is_not_a_window_pricer_is_refused(dem_path):
    with pytest.raises(InvalidParameterError, match="cost_from must be a CostSpec or a callable"):
        plan_coarse_to_fine(dem_path, START, GOAL, cost_from="husky")
    with pytest.raises(InvalidParameterError, match="cost_from must return an EnergyCost"):
        plan_coarse_to_fine(dem_path, START, GOAL, cost_from=lambda tmap: 3.0)
    other = CostSpec().build(procedural_map((8, 8), 1.0, seed=1))
    with pytest.raises(InvalidParameterError, match="cost_from must return an EnergyCost on the TerrainMap"):
        plan_coarse_to_fine(dem_path, START, GOAL, cost_from=lambda tmap: other)

    def by_height(tmap):  # a cost that depends on the window's content: tables differ between windows
        speed = 0.5 if tmap.origin_xy_m[1] < 40 else 0.9
        return CostSpec(speed_mps=speed).build(tmap)

    with pytest.raises(InvalidParameterError, match="different energy tables"):
        plan_coarse_to_fine(dem_path, START, GOAL, CoarseOptions(window_cells=16), cost_from=by_height)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"factor": 1}, InvalidParameterError, "factor must be >= 2"),
        ({"factor": 2.5}, InvalidParameterError, "factor"),
        ({"factor": 100}, InvalidParameterError, "fewer than 2 x 2"),
        ({"corridor_m": 0.0}, InvalidParameterError, "corridor_m must be > 0"),
        ({"corridor_m": float("nan")}, InvalidParameterError, "corridor_m"),
        ({"window_cells": 10}, InvalidParameterError, r"window_cells=10 is not a multiple of factor=4.*window_cells=8"),
        ({"window_cells": 1}, InvalidParameterError, "window_cells must be >= 2"),
        ({"window_cells": "big"}, InvalidParameterError, "window_cells"),
        ({"band": 2}, InvalidParameterError, "band must be an integer in 1..1"),
    ],
)
def test_bad_arguments(dem_path, kwargs, error, match):
    with pytest.raises(error, match=match):
        plan_coarse_to_fine(dem_path, START, GOAL, CoarseOptions(**kwargs))


def test_bad_points(dem_path, tmp_path):
    with pytest.raises(OutOfBoundsError, match=r"start/goal point \(-1.0, 6.5\) m lies outside the map bounds"):
        plan_coarse_to_fine(dem_path, (-1.0, 6.5), GOAL)
    with pytest.raises(OutOfBoundsError, match="outside"):
        plan_coarse_to_fine(dem_path, START, (97.5, 10.0))
    with pytest.raises(InvalidParameterError, match="start equals goal"):
        plan_coarse_to_fine(dem_path, START, START)
    with pytest.raises(InvalidParameterError, match="start/goal"):
        plan_coarse_to_fine(dem_path, (float("nan"), 1.0), GOAL)
    path = ridge_dem(tmp_path / "ridge.tif")
    with pytest.raises(BlockedPositionError, match=r"goal_xy_m \(31.5, 10.5\) m lies on a blocked cell .* row 10, col 31"):
        plan_coarse_to_fine(path, (4.5, 4.5), (31.5, 10.5), CoarseOptions(factor=4))
    whole = CostSpec().build(read_geotiff(path))
    with pytest.raises(BlockedPositionError, match=r"row 10, col 31"):  # the same message as on the whole map
        plan_coarse_to_fine(whole, (4.5, 4.5), (31.5, 10.5), CoarseOptions(factor=4))
    with pytest.raises(BlockedPositionError, match=r"start_xy_m \(31.5, 0.5\) m .* row 0, col 31"):  # at the edge
        plan_coarse_to_fine(path, (31.5, 0.5), (4.5, 4.5), CoarseOptions(factor=4))


def test_bad_files(tmp_path):
    with pytest.raises(FileFormatError, match="does not exist"):
        plan_coarse_to_fine(tmp_path / "missing.tif", START, GOAL)
    (tmp_path / "text.tif").write_text("not a raster")
    with pytest.raises(FileFormatError, match="cannot read"):
        plan_coarse_to_fine(tmp_path / "text.tif", START, GOAL)
    z = np.zeros((40, 40))
    z[30, 35] = -9999.0
    holed = write_dem(tmp_path / "holed.tif", z, nodata=-9999.0)
    with pytest.raises(NodataError, match=r"holed.tif.* 1 nodata/NaN cells in map rows 23..32, cols 31..39"):
        plan_coarse_to_fine(holed, (2.5, 2.5), (10.5, 3.5), CoarseOptions(factor=4, window_cells=8))
    geo = tmp_path / "geo.tif"
    with rasterio.open(geo, "w", driver="GTiff", height=10, width=10, count=1, dtype="float32", crs="EPSG:4326",
                       transform=rasterio.Affine(0.001, 0.0, 15.0, 0.0, -0.001, 45.0)) as dst:
        dst.write(np.zeros((10, 10), "float32"), 1)
    with pytest.raises(FileFormatError, match="units are not metres"):
        plan_coarse_to_fine(geo, (15.0005, 44.9995), (15.0055, 44.9955))


# ------------------------------------------------------------------ the command line
def test_plan_windowed_from_the_command_line_equals_the_whole_map_plan(dem_path, tmp_path, capsys):
    from terrawatt_cli import main

    args = ["plan", "--map", str(dem_path), "--start", *map(str, START), "--goal", *map(str, GOAL),
            "--coarse-factor", "4"]
    assert main([*args, "--windowed", "--out", str(tmp_path / "w")]) == 0
    out = capsys.readouterr().out
    assert "read by windows" in out and "coarse-to-fine (x4)" in out
    assert main([*args, "--out", str(tmp_path / "m")]) == 0
    w, m = (json.loads((tmp_path / d / "route.json").read_text()) for d in ("w", "m"))
    assert w["windowed"] is True and m["windowed"] is False
    assert w["routes"]["min_energy"]["waypoints_m"] == m["routes"]["min_energy"]["waypoints_m"]
    assert w["routes"]["min_energy"]["energy_j"] == m["routes"]["min_energy"]["energy_j"]
    assert w["coarse_waypoints_m"] == m["coarse_waypoints_m"] and w["map_crs"] == "EPSG:32633"
    gw, gm = (json.loads((tmp_path / d / "route.geojson").read_text()) for d in ("w", "m"))
    assert gw["features"][0]["geometry"] == gm["features"][0]["geometry"]
    assert (tmp_path / "w" / "route.png").stat().st_size > 0


def test_plan_windowed_in_chained_fine_windows_writes_its_files(dem_path, tmp_path, capsys):
    from terrawatt_cli import main

    args = ["plan", "--map", str(dem_path), "--start", *map(str, START), "--goal", *map(str, GOAL),
            "--coarse-factor", "4", "--windowed"]
    assert main([*args, "--out", str(tmp_path / "one")]) == 0
    assert main([*args, "--fine-window-cells", "2500", "--out", str(tmp_path / "chain")]) == 0
    one, chain = (json.loads((tmp_path / d / "route.json").read_text()) for d in ("one", "chain"))
    assert one["coarse_to_fine"]["fine_windows"] == 1 < chain["coarse_to_fine"]["fine_windows"]
    assert chain["coarse_to_fine"]["fine_window_max_cells"] <= 2500
    # no one fine map holds a chained route: the GeoJSON still comes, with the coarse map's elevations
    feature = json.loads((tmp_path / "chain" / "route.geojson").read_text())["features"][0]
    assert len(feature["geometry"]["coordinates"]) == len(chain["routes"]["min_energy"]["waypoints_m"])
    assert chain["routes"]["min_energy"]["energy_j"] == pytest.approx(one["routes"]["min_energy"]["energy_j"], rel=0.03)
    assert main([*args, "--fine-window-cells", "0", "--out", str(tmp_path / "bad")]) == 2
    assert "--fine-window-cells must be a number > 0" in capsys.readouterr().err


def test_plan_windowed_whole_map_figure_and_no_route(tmp_path, capsys):
    from terrawatt_cli import main

    path = ridge_dem(tmp_path / "ridge.tif", (0, 0))
    rc = main(["plan", "--map", str(path), "--start", "4.5", "4.5", "--goal", "60.5", "4.5", "--coarse-factor", "4",
               "--windowed", "--whole-map", "--out", str(tmp_path / "o")])
    assert rc == 1 and "no route: status 'infeasible'" in capsys.readouterr().out
    assert json.loads((tmp_path / "o" / "route.json").read_text())["status"] == "infeasible"
    assert (tmp_path / "o" / "route.png").is_file() and not (tmp_path / "o" / "route.geojson").exists()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        ([], "--windowed plans coarse-to-fine; give --coarse-factor F too"),
        (["--coarse-factor", "1"], "--coarse-factor must be an integer >= 2"),
        (["--coarse-factor", "4", "--fill-nodata", "nearest"], "cannot apply --fill-nodata"),
        (["--coarse-factor", "4", "--reproject", "utm", "--cell-size", "5"], "cannot apply --reproject"),
        (["--coarse-factor", "4", "--unknown-ground", "none"], "--unknown-ground none refuses every cell"),
        (["--coarse-factor", "4", "--unknown-ground", "lava"], "--unknown-ground must be a ground preset"),
        (["--coarse-factor", "4", "--corridor", "0"], "--corridor must be a number > 0"),
        (["--coarse-factor", "4", "--speed", "-1"], "--speed must be a number > 0"),
    ],
)
def test_plan_windowed_flags_are_checked(dem_path, tmp_path, capsys, extra, message):
    from terrawatt_cli import main

    rc = main(["plan", "--map", str(dem_path), "--start", "5.5", "6.5", "--goal", "90.5", "120.5", "--windowed",
               *extra, "--out", str(tmp_path / "o")])
    assert rc == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "o" / "route.json").exists()


def test_plan_windowed_needs_a_geotiff(tmp_path, capsys):
    from terrawatt_cli import main

    npz = tmp_path / "map.npz"
    procedural_map((16, 16), 1.0, seed=0).save(npz)
    rc = main(["plan", "--map", str(npz), "--start", "1.5", "1.5", "--goal", "12.5", "12.5", "--coarse-factor", "2",
               "--windowed", "--out", str(tmp_path / "o")])
    assert rc == 2 and "--windowed reads GeoTIFF DEMs" in capsys.readouterr().err
