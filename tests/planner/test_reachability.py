"""Energy reachability: equal to single lattice routes, obstacles, budgets, round trips, files, figure and CLI."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

import terrain
from planner import EnergyCost, Lattice, Reachability, reachability
from planner.reachability import lattice_move_energies
from terrawatt_base.errors import (
    BlockedPositionError,
    FileFormatError,
    FormatVersionError,
    InvalidParameterError,
    OutOfBoundsError,
    UnknownNameError,
)
from terrawatt_cli import main

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
DEPOT = (17.3, 21.6)  # not a cell centre: joined to the nodes within 1.5 cells, like a lattice query's start


@pytest.fixture(scope="module")
def hilly_cost() -> EnergyCost:
    """36 x 44 cells of 1 m: hills, four grounds, rocks and a wall with a gap."""
    tmap = terrain.procedural_map((36, 44), 1.0, seed=7, obstacle_fraction=0.04, n_walls=1, slope_deg=10.0)
    obstacle = np.array(tmap.obstacle)
    r, c = tmap.rowcol(*DEPOT)
    obstacle[r - 1:r + 2, c - 1:c + 2] = False  # keep the depot free whatever the seed draws
    tmap["obstacle"] = obstacle
    return EnergyCost.from_presets(tmap, speed_mps=0.5)


@pytest.fixture(scope="module")
def hilly_reach(hilly_cost) -> Reachability:
    return reachability(hilly_cost, DEPOT, round_trip=True)


def _sample_cells(cost: EnergyCost, n: int, seed: int = 0) -> list[tuple[int, int]]:
    rng = np.random.default_rng(seed)
    rows, cols = cost.shape
    return [(int(rng.integers(rows)), int(rng.integers(cols))) for _ in range(n)]


def _centre(cost: EnergyCost, r: int, c: int) -> tuple[float, float]:
    x, y = cost.terrain.xy(r, c)
    return float(x), float(y)


# ---------------------------------------------------------------- equal to single routes
def test_forward_energy_equals_the_lattice_planners_route_at_sampled_cells(hilly_cost, hilly_reach):
    lat = Lattice(hilly_cost, stride_cells=1)
    through_lattice = 0
    for r, c in _sample_cells(hilly_cost, 25):
        goal = _centre(hilly_cost, r, c)
        path = lat.shortest_path(DEPOT, goal)
        fwd = hilly_reach.forward_energy_j[r, c]
        if not path.found:
            assert fwd == math.inf
            continue
        # the lattice query also tries the straight depot-goal segment; the field is the lattice's
        direct = float(hilly_cost.segment_energy_j(np.array(DEPOT), np.array(goal))[0])
        assert min(fwd, direct) == pytest.approx(path.objective, rel=1e-9)
        assert fwd >= path.objective * (1 - 1e-9)
        through_lattice += fwd < direct
    assert through_lattice >= 10  # most samples are routes through the lattice, not the straight line


def test_round_trip_equals_the_route_there_plus_the_route_back(hilly_cost, hilly_reach):
    lat = Lattice(hilly_cost, stride_cells=1)
    for r, c in _sample_cells(hilly_cost, 15, seed=1):
        cell = _centre(hilly_cost, r, c)
        there = lat.shortest_path(DEPOT, cell)
        back = lat.shortest_path(cell, DEPOT)
        rt = hilly_reach.round_trip_energy_j[r, c]
        if not (there.found and back.found):
            assert rt == math.inf
            continue
        direct_back = float(hilly_cost.segment_energy_j(np.array(cell), np.array(DEPOT))[0])
        assert min(hilly_reach.back_energy_j[r, c], direct_back) == pytest.approx(back.objective, rel=1e-9)
    np.testing.assert_array_equal(hilly_reach.round_trip_energy_j,
                                  hilly_reach.forward_energy_j + hilly_reach.back_energy_j)


def test_every_cell_equals_scipy_dijkstra_on_the_lattice_graph_and_its_transpose(hilly_cost, hilly_reach):
    lat = Lattice(hilly_cost, stride_cells=1)
    g = lat.graph("energy")
    n = lat.n_nodes
    xy = lat.node_xy(np.arange(n))
    near = np.flatnonzero(np.hypot(xy[:, 0] - DEPOT[0], xy[:, 1] - DEPOT[1]) <= 1.5)
    out_j = hilly_cost.segment_energy_j(np.broadcast_to(DEPOT, (near.size, 2)), xy[near])
    back_j = hilly_cost.segment_energy_j(xy[near], np.broadcast_to(DEPOT, (near.size, 2)))
    for graph, links, raster in ((g, out_j, hilly_reach.forward_energy_j), (g.T.tocsr(), back_j,
                                                                           hilly_reach.back_energy_j)):
        ok = np.isfinite(links)
        rows = np.concatenate([graph.tocoo().row, np.full(ok.sum(), n)])
        cols = np.concatenate([graph.tocoo().col, near[ok]])
        data = np.concatenate([graph.tocoo().data, links[ok]])
        ext = csr_matrix((data, (rows, cols)), shape=(n + 1, n + 1))
        expected = dijkstra(ext, directed=True, indices=n)[:n].reshape(hilly_cost.shape)
        np.testing.assert_allclose(raster, expected, rtol=1e-9)
        assert np.array_equal(np.isinf(raster), np.isinf(expected))


def _one_way_cost(tmap: terrain.TerrainMap, max_uphill_grade: float) -> EnergyCost:
    """Custom tables: 100 J/m plus 2000 J/m per unit grade uphill, undrivable above ``max_uphill_grade``."""
    grades = np.linspace(-np.tan(np.radians(20.0)), np.tan(np.radians(20.0)), 41)
    table = 100.0 + 2000.0 * np.clip(grades, 0.0, None)
    table[grades > max_uphill_grade] = np.inf
    return EnergyCost(tmap, np.zeros(tmap.shape, np.int32), table[None, :], np.ones((1, 5)), speed_mps=0.5,
                      battery_voltage_v=24.0, turn_rate_radps=1.0)


@pytest.mark.parametrize("case", ["hilly", "offset", "steep", "example"])
def test_stride1_move_kernel_equals_the_lattice_kernel(case):
    from planner.kernels import UNIT_HALF, lattice_weights, unit_lattice_weights
    from planner.lattice import LATTICE_OFFSETS

    assert np.array_equal(UNIT_HALF, LATTICE_OFFSETS[:8])
    if case == "hilly":
        cost = EnergyCost.from_presets(terrain.procedural_map((45, 52), 1.0, seed=3, n_walls=2, obstacle_fraction=0.05))
    elif case == "offset":  # odd cell size, far origin, steep ground: coordinates do not round like 1 m cells
        tmap = terrain.procedural_map((41, 37), 0.7, seed=5, origin_xy_m=(4321.5, -77.3), slope_deg=15.0, n_walls=1)
        cost = EnergyCost.from_presets(tmap)
    elif case == "steep":  # moves undrivable uphill only: one direction inf, the other finite
        cost = _one_way_cost(terrain.ramp_map((20, 24), 0.5, grade=0.12), max_uphill_grade=0.1)
    else:
        cost = EnergyCost.from_presets(terrain.example_map())
    arr = cost.arrays
    rows, cols = cost.shape
    ref = lattice_weights(arr.cells, arr.grade_table, arr.geo, 1, 0, rows, cols, LATTICE_OFFSETS[:8])
    got = unit_lattice_weights(arr.cells, arr.grade_table, arr.geo, rows, cols)
    assert np.array_equal(np.isinf(got), np.isinf(ref))
    np.testing.assert_allclose(got[np.isfinite(ref)], ref[np.isfinite(ref)], rtol=1e-9)
    if case == "steep":
        one_way = np.isinf(ref[:, :8]) != np.isinf(ref[:, 8:])
        assert one_way.any()


def test_a_ramp_too_steep_to_climb_is_reached_only_from_above():
    # Rises 0.12 along +x; every lattice move gaining x climbs at least 0.12 / sqrt(5) = 0.054 (a knight
    # move), above the 0.05 the ground allows: the robot cannot gain height, even by switchbacks.
    tmap = terrain.ramp_map((12, 40), 1.0, grade=0.12)
    cost = _one_way_cost(tmap, max_uphill_grade=0.05)
    low = reachability(cost, (2.5, 6.5), round_trip=True)
    assert np.all(np.isfinite(low.forward_energy_j[:, :3])) and np.all(np.isinf(low.forward_energy_j[:, 3:]))
    high = reachability(cost, (39.5, 6.5), round_trip=True)  # the top column
    assert np.all(np.isfinite(high.forward_energy_j))  # everything is downhill or level from the top
    assert np.all(np.isinf(high.round_trip_energy_j[:, :39]))  # but nothing below comes back up
    assert not high.reachable[:, :39].any() and high.reachable[:, 39].all()
    # a ground that climbs 0.1 switchbacks up the same ramp (knight moves climb 0.054)
    zigzag = reachability(_one_way_cost(tmap, max_uphill_grade=0.1), (2.5, 6.5))
    assert np.all(np.isfinite(zigzag.forward_energy_j))


# ---------------------------------------------------------------- obstacles and geometry
def test_obstacle_cells_and_cells_cut_off_are_inf(hilly_cost, hilly_reach, wall_map):
    blocked = hilly_cost.blocked
    assert blocked.any()
    for raster in (hilly_reach.forward_energy_j, hilly_reach.back_energy_j, hilly_reach.round_trip_energy_j):
        assert np.all(np.isinf(raster[blocked]))
    assert not hilly_reach.reachable[blocked].any()
    closed = np.array(wall_map.obstacle)
    closed[:, 20] = True  # close the gap: the east half is cut off
    tmap = terrain.TerrainMap(wall_map.elevation_m, 1.0, ground=wall_map.ground, ground_names=wall_map.ground_names,
                              obstacle=closed)
    reach = reachability(EnergyCost.from_presets(tmap), (5.5, 5.5), round_trip=True)
    assert np.all(np.isinf(reach.forward_energy_j[:, 21:])) and np.all(np.isinf(reach.back_energy_j[:, 21:]))
    assert np.all(np.isfinite(reach.forward_energy_j[:, :20]))
    assert reach.reachable_area_m2 == 40 * 20


def test_flat_ground_costs_the_same_both_ways_and_grows_with_distance(flat_map):
    cost = EnergyCost.from_presets(flat_map)
    reach = reachability(cost, (7.25, 4.75), round_trip=True)
    np.testing.assert_allclose(reach.forward_energy_j, reach.back_energy_j, rtol=1e-12)
    r, c = flat_map.rowcol(7.25, 4.75)
    row = reach.forward_energy_j[r, c:]
    assert np.all(np.diff(row) > 0)  # farther east along the row costs more
    assert reach.farthest_reachable_m == pytest.approx(math.hypot(14.75 - 7.25, 9.75 - 4.75))  # the far corner cell


def test_on_a_ramp_uphill_costs_more_than_downhill(ramp_map):
    cost = EnergyCost.from_presets(ramp_map)
    depot = (10.25, 5.25)
    reach = reachability(cost, depot, round_trip=True)
    r, c = ramp_map.rowcol(*depot)
    up, down = reach.forward_energy_j[r, c + 12], reach.forward_energy_j[r, c - 12]  # 6 m east (uphill), west
    assert up > 1.5 * down
    # coming back from the uphill cell is downhill: cheaper than going there
    assert reach.back_energy_j[r, c + 12] < up
    assert reach.back_energy_j[r, c - 12] > down


def test_round_trip_is_at_least_the_way_out(hilly_reach):
    finite = np.isfinite(hilly_reach.round_trip_energy_j)
    assert finite.sum() > 1000
    assert np.all(hilly_reach.round_trip_energy_j[finite] >= hilly_reach.forward_energy_j[finite])
    assert np.all(np.isinf(hilly_reach.forward_energy_j[~finite]) | np.isinf(hilly_reach.back_energy_j[~finite]))


# ---------------------------------------------------------------- budgets
def test_budget_mask_is_monotone_in_the_budget_and_the_reserve_shrinks_it(hilly_cost):
    full = reachability(hilly_cost, DEPOT, round_trip=True)
    top = float(np.max(full.round_trip_energy_j[np.isfinite(full.round_trip_energy_j)]))
    previous = np.zeros(hilly_cost.shape, bool)
    areas = []
    for frac in (0.05, 0.2, 0.5, 0.8, 1.0):
        reach = reachability(hilly_cost, DEPOT, budget_j=frac * top, round_trip=True)
        assert np.all(reach.reachable[previous])  # every cell reachable on a smaller budget still is
        assert np.array_equal(reach.reachable, full.round_trip_energy_j <= frac * top)
        previous = reach.reachable
        areas.append(reach.reachable_area_m2)
    assert areas == sorted(areas) and areas[0] < areas[-1]
    assert np.array_equal(previous, np.isfinite(full.round_trip_energy_j))
    kept = reachability(hilly_cost, DEPOT, budget_j=top, reserve_j=0.5 * top, round_trip=True)
    assert np.array_equal(kept.reachable, full.round_trip_energy_j <= 0.5 * top)
    one_way = reachability(hilly_cost, DEPOT, budget_j=0.5 * top)
    assert one_way.reachable_area_m2 > kept.reachable_area_m2  # one way goes farther on the same energy
    assert one_way.back_energy_j is None and one_way.round_trip_energy_j is None


def test_figures_and_to_dict(hilly_cost):
    reach = reachability(hilly_cost, DEPOT, budget_j=20_000.0, reserve_j=4_000.0, round_trip=True)
    d = json.loads(json.dumps(reach.to_dict()))
    assert d["usable_energy_j"] == 16_000.0 and d["usable_energy_wh"] == pytest.approx(16_000 / 3600)
    assert d["reachable_cells"] == int(reach.reachable.sum()) > 0
    assert d["reachable_area_m2"] == d["reachable_cells"] * 1.0
    assert d["max_round_trip_energy_j"] <= 16_000.0
    assert d["max_round_trip_energy_j"] == float(np.max(reach.round_trip_energy_j[reach.reachable]))
    rows, cols = np.nonzero(reach.reachable)
    x, y = hilly_cost.terrain.xy(rows, cols)
    assert d["farthest_reachable_m"] == pytest.approx(np.max(np.hypot(x - DEPOT[0], y - DEPOT[1])))


def test_move_energies_are_cached_on_the_cost(flat_map):
    cost = EnergyCost.from_presets(flat_map)
    w, first_s = lattice_move_energies(cost)
    again, cached_s = lattice_move_energies(cost)
    assert again is w and cached_s == 0.0 and first_s > 0.0
    assert w.shape == (flat_map.shape[0] * flat_map.shape[1], 16) and not w.flags.writeable
    assert reachability(cost, (3.0, 3.0)).graph_time_s == 0.0


def test_result_is_frozen_and_its_rasters_read_only(hilly_reach):
    with pytest.raises(dataclasses.FrozenInstanceError):
        hilly_reach.budget_j = 1.0
    with pytest.raises(ValueError):
        hilly_reach.forward_energy_j[0, 0] = 0.0
    with pytest.raises(ValueError):
        hilly_reach.reachable[0, 0] = True


# ---------------------------------------------------------------- bad input
def test_depot_in_an_obstacle_or_outside_the_map_is_a_clear_error(wall_map):
    cost = EnergyCost.from_presets(wall_map)
    with pytest.raises(BlockedPositionError, match=r"depot \(20\.5, 5\.0\) m lies on a blocked cell"):
        reachability(cost, (20.5, 5.0))
    with pytest.raises(OutOfBoundsError, match="depot point .* outside the map"):
        reachability(cost, (41.0, 5.0))
    with pytest.raises(InvalidParameterError, match="depot_xy_m must be finite"):
        reachability(cost, (math.nan, 5.0))
    with pytest.raises(InvalidParameterError, match="depot_xy_m must be one point"):
        reachability(cost, [(1.0, 1.0), (2.0, 2.0)])
    with pytest.raises(InvalidParameterError, match="depot_xy_m must have shape"):
        reachability(cost, (1.0, 2.0, 3.0))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"budget_j": 0.0}, "budget_j"),
        ({"budget_j": -5.0}, "budget_j"),
        ({"budget_j": math.nan}, "budget_j"),
        ({"budget_j": "lots"}, "budget_j"),
        ({"budget_j": 100.0, "reserve_j": -1.0}, "reserve_j"),
        ({"budget_j": 100.0, "reserve_j": 100.0}, "reserve_j must be below budget_j"),
        ({"reserve_j": 10.0}, "needs a budget_j"),
        ({"round_trip": "yes"}, "round_trip"),
    ],
)
def test_bad_budgets_and_flags_are_refused(flat_map, kwargs, message):
    cost = EnergyCost.from_presets(flat_map)
    with pytest.raises(InvalidParameterError, match=message):
        reachability(cost, (3.0, 3.0), **kwargs)


def test_a_cost_that_is_not_an_energy_cost_is_refused(flat_map):
    with pytest.raises(InvalidParameterError, match="cost must be an EnergyCost"):
        reachability(flat_map, (3.0, 3.0))
    with pytest.raises(InvalidParameterError, match="cost must be an EnergyCost"):
        lattice_move_energies("cost")


# ---------------------------------------------------------------- files and figure
def test_npz_round_trip_and_bad_files(tmp_path, hilly_cost):
    reach = reachability(hilly_cost, DEPOT, budget_j=20_000.0, reserve_j=1_000.0, round_trip=True)
    path = reach.write(tmp_path / "reach.npz")
    back = Reachability.load(path)
    for name in ("forward_energy_j", "back_energy_j", "round_trip_energy_j", "blocked", "reachable"):
        np.testing.assert_array_equal(getattr(back, name), getattr(reach, name))
    assert (back.budget_j, back.reserve_j, back.round_trip, back.depot_xy_m) == (20_000.0, 1_000.0, True, DEPOT)
    assert back.grid == reach.grid
    one_way = reachability(hilly_cost, DEPOT)
    again = Reachability.load(one_way.write(tmp_path / "one.npz"))
    assert again.budget_j is None and again.back_energy_j is None
    with pytest.raises(InvalidParameterError, match="end in '.npz', '.tif' or '.tiff'"):
        reach.write(tmp_path / "reach.csv")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(FileFormatError, match="corrupt"):
        Reachability.load(tmp_path / "junk.npz")
    with pytest.raises(FileFormatError, match="missing"):
        Reachability.load(tmp_path / "absent.npz")
    np.savez(tmp_path / "future.npz", __magic__=np.array("terrawatt-reachability"), __version__=np.array(99))
    with pytest.raises(FormatVersionError, match="version 99"):
        Reachability.load(tmp_path / "future.npz")
    np.savez(tmp_path / "partial.npz", __magic__=np.array("terrawatt-reachability"), __version__=np.array(1))
    with pytest.raises(FileFormatError, match="lacks entry"):
        Reachability.load(tmp_path / "partial.npz")


def test_geotiff_keeps_the_grid_and_crs(tmp_path, hilly_cost):
    rasterio = pytest.importorskip("rasterio", reason="GeoTIFF output needs the geo extra (rasterio)")
    tmap = hilly_cost.terrain.copy()
    tmap.crs = "EPSG:32633"
    cost = EnergyCost.from_presets(tmap)
    reach = reachability(cost, DEPOT, budget_j=20_000.0, round_trip=True)
    path = reach.write(tmp_path / "reach.tif")
    with rasterio.open(path) as src:
        assert src.crs.to_string() == "EPSG:32633"
        band = src.read(1)[::-1]  # north-up in the file
        assert src.transform.a == 1.0 and src.bounds.top == tmap.bounds[3]
    np.testing.assert_array_equal(band, reach.round_trip_energy_j)
    mask = reach.write(tmp_path / "mask.tif", layer="reachable")
    with rasterio.open(mask) as src:
        np.testing.assert_array_equal(src.read(1)[::-1], reach.reachable.astype(np.uint8))
    with pytest.raises(UnknownNameError, match="layer must be one of"):
        reach.write(tmp_path / "x.tif", layer="slope")
    with pytest.raises(UnknownNameError, match="only for a round trip"):
        reachability(cost, DEPOT).write(tmp_path / "y.tif", layer="back")


def test_plot_writes_a_png_and_checks_its_path_first(tmp_path, hilly_cost):
    reach = reachability(hilly_cost, DEPOT, budget_j=8_000.0, round_trip=True)
    assert 0 < reach.reachable_fraction < 1  # the outline is drawn
    path = reach.plot(tmp_path / "reach.png")
    assert path.read_bytes()[:8] == PNG_MAGIC
    (tmp_path / "folder.png").mkdir()
    with pytest.raises(InvalidParameterError):
        reach.plot(tmp_path / "folder.png")


def test_plot_draws_into_the_callers_axes_with_its_colour_bar_beside_them(tmp_path, hilly_cost):
    from matplotlib.figure import Figure

    reach = reachability(hilly_cost, DEPOT, budget_j=8_000.0, round_trip=True)
    fig = Figure()
    left, right = fig.subplots(1, 2)
    assert reach.plot(ax=right, title="mine") is right
    assert len(right.images) >= 2 and right.collections  # field, obstacles; contours and the outline
    assert right.get_title() == "mine"
    assert any(t.get_text().startswith("reachable within") for t in right.get_legend().texts)
    assert len(fig.axes) == 3 and fig.axes[2].get_ylabel() == "least energy round trip (Wh)"
    assert not left.has_data()
    with pytest.raises(InvalidParameterError, match="got neither"):
        reach.plot()
    with pytest.raises(InvalidParameterError, match="not both"):
        reach.plot(tmp_path / "reach.png", ax=left)
    with pytest.raises(InvalidParameterError, match="ax must be a matplotlib Axes, got 'Figure'"):
        reach.plot(ax=fig)
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------- CLI
def test_cli_writes_raster_json_and_plot_and_prints_the_figures(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    out = tmp_path / "out"
    rc = main(["reach", "--map", str(path), "--depot", "5.5", "5.5", "--battery-ah", "0.05", "--voltage", "24",
               "--reserve", "10", "--round-trip", "--out", str(out)])
    text = capsys.readouterr().out
    assert rc == 0
    assert "reachable area" in text and "max round-trip energy" in text
    data = json.loads((out / "reach.json").read_text())
    assert data["budget_j"] == pytest.approx(0.05 * 24 * 3600) and data["reserve_j"] == pytest.approx(432.0)
    reach = Reachability.load(out / "reach.npz")
    assert data["reachable_cells"] == int(reach.reachable.sum()) > 0
    assert f"{data['reachable_area_m2']:,.0f} m^2" in text
    assert (out / "reach.png").read_bytes()[:8] == PNG_MAGIC
    assert not (out / "reach.tif").exists()


def test_cli_on_a_geotiff_writes_a_geotiff(tmp_path, capsys, wall_map):
    pytest.importorskip("rasterio", reason="GeoTIFF maps need the geo extra (rasterio)")
    tmap = wall_map.copy()
    tmap.crs = "EPSG:32633"
    dem = terrain.write_geotiff(tmap, tmp_path / "dem.tif")
    rc = main(["reach", "--map", str(dem), "--depot", "5.5", "5.5", "--battery-ah", "1", "--out", str(tmp_path / "o")])
    capsys.readouterr()
    assert rc == 0 and (tmp_path / "o" / "reach.tif").is_file() and not (tmp_path / "o" / "reach.npz").exists()


def test_cli_exits_1_when_no_cell_is_reachable(tmp_path, capsys):
    rc = main(["reach", "--example", "--depot", "10.3", "10.3", "--battery-ah", "1e-9", "--out", str(tmp_path)])
    assert rc == 1
    assert "no cell is reachable" in capsys.readouterr().out
    assert json.loads((tmp_path / "reach.json").read_text())["reachable_cells"] == 0


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--battery-ah", "-1"], "--battery-ah must be a number > 0"),
        (["--battery-ah", "1", "--reserve", "100"], "--reserve must be a percentage in [0, 100)"),
        (["--battery-ah", "1", "--voltage", "0"], "--voltage must be a number > 0"),
        (["--battery-ah", "1", "--depot", "500", "5"], "outside the map"),
        (["--battery-ah", "1", "--depot", "nan", "5"], "--depot must be two finite coordinates"),
        (["--battery-ah", "1", "--max-slope-deg", "95"], "--max-slope-deg"),
        (["--battery-ah", "1", "--robot", "tank"], "tank"),
    ],
)
def test_cli_bad_input_exits_2_with_one_line(tmp_path, capsys, extra, message):
    rc = main(["reach", "--example", "--out", str(tmp_path / "o"), *extra])
    err = capsys.readouterr().err
    assert rc == 2
    assert message in err and err.count("\n") == 1
    assert not (tmp_path / "o" / "reach.json").exists()


def test_cli_map_needs_a_depot_and_a_free_one(tmp_path, capsys, wall_map):
    path = wall_map.save(tmp_path / "wall.npz")
    assert main(["reach", "--map", str(path), "--battery-ah", "1", "--out", str(tmp_path / "o")]) == 2
    assert "--depot X Y is required with --map" in capsys.readouterr().err
    assert main(["reach", "--map", str(path), "--depot", "20.5", "5", "--battery-ah", "1",
                 "--out", str(tmp_path / "o")]) == 2
    assert "blocked cell" in capsys.readouterr().err
    (tmp_path / "file").write_text("x")
    assert main(["reach", "--example", "--battery-ah", "1", "--out", str(tmp_path / "file")]) == 2
    assert "--out" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["reach", "--example", "--map", str(path), "--battery-ah", "1"])
    assert exc.value.code == 2
    capsys.readouterr()


def test_cli_missing_map_file_exits_2(tmp_path, capsys):
    rc = main(["reach", "--map", str(Path(tmp_path) / "nope.npz"), "--depot", "1", "1", "--battery-ah", "1",
               "--out", str(tmp_path / "o")])
    assert rc == 2
    assert "nope.npz" in capsys.readouterr().err
