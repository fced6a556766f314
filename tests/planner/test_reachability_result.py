"""Tests of planner.reachability_result: the Reachability figures, frozen read-only rasters, npz and GeoTIFF files."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from reach_samples import DEPOT, hilly_cost, hilly_reach  # noqa: F401  (fixtures)

from planner import Reachability, reachability
from planner.cost_spec import CostSpec
from terrawatt_base.errors import FileFormatError, FormatVersionError, InvalidParameterError, UnknownNameError


def test_figures_and_to_dict(hilly_cost):
    reach = reachability(hilly_cost, DEPOT, budget_j=20_000.0, reserve_j=4_000.0, round_trip=True)
    d = json.loads(json.dumps(reach.to_dict()))
    assert (d["format"], d["format_version"]) == ("terrawatt-reachability", 1)  # a result document (reach.json)
    assert d["usable_energy_j"] == 16_000.0 and d["usable_energy_wh"] == pytest.approx(16_000 / 3600)
    assert d["reachable_cells"] == int(reach.reachable.sum()) > 0
    assert d["reachable_area_m2"] == d["reachable_cells"] * 1.0
    assert d["max_round_trip_energy_j"] <= 16_000.0
    assert d["max_round_trip_energy_j"] == float(np.max(reach.round_trip_energy_j[reach.reachable]))
    rows, cols = np.nonzero(reach.reachable)
    x, y = hilly_cost.terrain.xy(rows, cols)
    assert d["farthest_reachable_m"] == pytest.approx(np.max(np.hypot(x - DEPOT[0], y - DEPOT[1])))


def test_without_a_header_the_answer_says_the_search_alone(hilly_cost, tmp_path):
    reach = reachability(hilly_cost, DEPOT, budget_j=20_000.0, round_trip=True)
    assert reach.priced is None and reach.terrain is None and reach.model is None
    lines = reach.summary().splitlines()
    assert lines[0].startswith("reachable area") and not any(s.startswith(("map", "total")) for s in lines)
    assert "map" not in reach.to_dict() and "raster" not in reach.to_dict("r.npz")
    assert [p.name for p in reach.write(tmp_path)] == ["reach.npz", "reach.json", "reach.png"]
    assert json.loads((tmp_path / "reach.json").read_text()) == json.loads(json.dumps(reach.to_dict()))
    with pytest.raises(InvalidParameterError, match="priced and battery come together"):
        dataclasses.replace(reach, battery=object())


def test_result_is_frozen_and_its_rasters_read_only(hilly_reach):
    with pytest.raises(dataclasses.FrozenInstanceError):
        hilly_reach.budget_j = 1.0
    with pytest.raises(ValueError):
        hilly_reach.forward_energy_j[0, 0] = 0.0
    with pytest.raises(ValueError):
        hilly_reach.reachable[0, 0] = True


# ---------------------------------------------------------------- files and figure
def test_npz_round_trip_and_bad_files(tmp_path, hilly_cost):
    reach = reachability(hilly_cost, DEPOT, budget_j=20_000.0, reserve_j=1_000.0, round_trip=True)
    path = reach.write_raster(tmp_path / "reach.npz")
    back = Reachability.load(path)
    for name in ("forward_energy_j", "back_energy_j", "round_trip_energy_j", "blocked", "reachable"):
        np.testing.assert_array_equal(getattr(back, name), getattr(reach, name))
    assert (back.budget_j, back.reserve_j, back.round_trip, back.depot_xy_m) == (20_000.0, 1_000.0, True, DEPOT)
    assert back.grid == reach.grid
    one_way = reachability(hilly_cost, DEPOT)
    again = Reachability.load(one_way.write_raster(tmp_path / "one.npz"))
    assert again.budget_j is None and again.back_energy_j is None
    with pytest.raises(InvalidParameterError, match="end in '.npz', '.tif' or '.tiff'"):
        reach.write_raster(tmp_path / "reach.csv")
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
    cost = CostSpec().build(tmap)
    reach = reachability(cost, DEPOT, budget_j=20_000.0, round_trip=True)
    path = reach.write_raster(tmp_path / "reach.tif")
    with rasterio.open(path) as src:
        assert src.crs.to_string() == "EPSG:32633"
        band = src.read(1)[::-1]  # north-up in the file
        assert src.transform.a == 1.0 and src.bounds.top == tmap.bounds[3]
    np.testing.assert_array_equal(band, reach.round_trip_energy_j)
    mask = reach.write_raster(tmp_path / "mask.tif", layer="reachable")
    with rasterio.open(mask) as src:
        np.testing.assert_array_equal(src.read(1)[::-1], reach.reachable.astype(np.uint8))
    with pytest.raises(UnknownNameError, match="layer must be one of"):
        reach.write_raster(tmp_path / "x.tif", layer="slope")
    with pytest.raises(UnknownNameError, match="only for a round trip"):
        reachability(cost, DEPOT).write_raster(tmp_path / "y.tif", layer="back")
