"""Energy costmaps: per-cell J/m statistics over headings on known maps, and their float32 GeoTIFF round trip."""

from __future__ import annotations

import numpy as np
import pytest

import terrain
from planner import EnergyCost, energy_costmap
from planner.cost_spec import CostSpec
from planner.energy_costmap import COSTMAP_STATISTICS, EnergyCostmap, read_energy_geotiff, write_energy_geotiff
from terrawatt_base.errors import FileFormatError, InvalidParameterError, UnknownNameError


def _per_metre(cost: EnergyCost, a, b) -> float:
    return float(cost.segment_energy_j([a], [b])[0]) / float(np.hypot(b[0] - a[0], b[1] - a[1]))


@pytest.mark.parametrize("statistic", COSTMAP_STATISTICS)
def test_a_flat_cell_costs_the_level_energy_per_metre_in_every_statistic(flat_map, statistic):
    cost = CostSpec().build(flat_map)
    costmap = energy_costmap(cost, statistic=statistic)
    level = _per_metre(cost, (0.25, 0.25), (12.25, 0.25))
    assert costmap.energy_per_metre_j.shape == flat_map.shape and costmap.statistic == statistic
    np.testing.assert_allclose(costmap.energy_per_metre_j, level, rtol=1e-12)
    assert costmap.grid == flat_map.grid and costmap.speed_mps == 0.5 and costmap.crs is None


def test_on_a_ramp_max_is_uphill_min_at_most_downhill_and_mean_the_average_over_headings(ramp_map):
    cost = CostSpec().build(ramp_map)
    by = {s: energy_costmap(cost, statistic=s).energy_per_metre_j[10, 20] for s in COSTMAP_STATISTICS}
    centre = np.array([10.25, 5.25])
    uphill = _per_metre(cost, centre - [2.0, 0.0], centre + [2.0, 0.0])
    downhill = _per_metre(cost, centre + [2.0, 0.0], centre - [2.0, 0.0])
    assert uphill > downhill
    assert by["max"] == pytest.approx(uphill, rel=1e-12)
    assert by["min"] <= downhill and by["min"] < by["mean"] < by["max"]
    theta = np.linspace(0.0, 2.0 * np.pi, 721)[:-1]
    ends = centre + 0.2 * np.column_stack([np.cos(theta), np.sin(theta)])  # inside the cell's row of equal cells
    sampled = cost.segment_energy_j(np.repeat(centre[None], theta.size, axis=0), ends) / 0.2
    assert by["mean"] == pytest.approx(sampled.mean(), rel=1e-4)
    assert by["min"] == pytest.approx(sampled.min(), rel=1e-4)


def test_blocked_cells_are_nan(wall_map):
    cost = CostSpec().build(wall_map)
    costmap = energy_costmap(cost)
    np.testing.assert_array_equal(costmap.blocked, wall_map.obstacle)
    assert np.isfinite(costmap.energy_per_metre_j[~wall_map.obstacle]).all()


def test_cells_steeper_than_the_limit_are_blocked_too():
    tmap = terrain.procedural_map((40, 50), 1.0, seed=3)
    cost = CostSpec(max_slope_deg=8.0).build(tmap)
    costmap = energy_costmap(cost)
    assert (tmap.slope_rad > np.radians(8.0)).any()
    np.testing.assert_array_equal(costmap.blocked, cost.blocked)


def test_geotiff_round_trip_keeps_values_grid_crs_and_the_north_up_order(tmp_path):
    rasterio = pytest.importorskip("rasterio", reason="GeoTIFF needs the geo extra (rasterio)")
    tmap = terrain.procedural_map((30, 40), 2.0, seed=5, origin_xy_m=(512_000.0, 4_990_000.0))
    tmap.crs = "EPSG:32633"
    costmap = energy_costmap(CostSpec(speed_mps=0.8).build(tmap), statistic="max")
    path = write_energy_geotiff(tmp_path / "energy.tif", costmap)
    back = read_energy_geotiff(path)
    np.testing.assert_array_equal(back.energy_per_metre_j, costmap.energy_per_metre_j.astype(np.float32))
    assert back.grid == costmap.grid and back.crs == "EPSG:32633"
    assert back.statistic == "max" and back.speed_mps == 0.8
    with rasterio.open(path) as src:
        assert src.dtypes == ("float32",) and np.isnan(src.nodata) and src.units == ("J/m",)
        assert tuple(src.transform)[:6] == (2.0, 0.0, 512_000.0, 0.0, -2.0, 4_990_060.0)
        first_row = src.read(1)[0]
    np.testing.assert_array_equal(first_row, costmap.energy_per_metre_j[-1].astype(np.float32))  # north first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["energy.tif"]


def test_blocked_cells_are_nodata_in_the_geotiff(tmp_path, wall_map):
    pytest.importorskip("rasterio", reason="GeoTIFF needs the geo extra (rasterio)")
    costmap = energy_costmap(CostSpec().build(wall_map))
    back = read_energy_geotiff(write_energy_geotiff(tmp_path / "wall.tif", costmap))
    np.testing.assert_array_equal(back.blocked, wall_map.obstacle)
    assert back.crs is None


def test_bad_arguments_are_refused(tmp_path, flat_map):
    cost = CostSpec().build(flat_map)
    with pytest.raises(UnknownNameError, match="statistic must be one of"):
        energy_costmap(cost, statistic="median")
    with pytest.raises(InvalidParameterError, match="n_headings must be >= 2"):
        energy_costmap(cost, n_headings=1)
    with pytest.raises(InvalidParameterError, match="cost must be an EnergyCost"):
        energy_costmap(flat_map)
    with pytest.raises(InvalidParameterError, match="has shape"):
        EnergyCostmap(np.zeros((2, 2)), flat_map.grid, None, "mean", 0.5)
    with pytest.raises(InvalidParameterError, match=">= 0"):
        EnergyCostmap(np.full(flat_map.shape, -1.0), flat_map.grid, None, "mean", 0.5)
    with pytest.raises(InvalidParameterError, match="'.tif' or '.tiff'"):
        write_energy_geotiff(tmp_path / "energy.png", energy_costmap(cost))


def test_reading_a_geotiff_that_is_not_a_costmap_fails_clearly(tmp_path, flat_map):
    pytest.importorskip("rasterio", reason="GeoTIFF needs the geo extra (rasterio)")
    dem = terrain.write_geotiff(flat_map, tmp_path / "dem.tif")
    with pytest.raises(FileFormatError, match="not a terrawatt energy costmap"):
        read_energy_geotiff(dem)
    junk = tmp_path / "junk.tif"
    junk.write_bytes(b"II*\x00junk")
    with pytest.raises(FileFormatError, match="cannot read GeoTIFF"):
        read_energy_geotiff(junk)
