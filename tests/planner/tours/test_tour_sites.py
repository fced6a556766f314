"""Tour sites and robots (planner.tours.sites): error rows, the library's errors, sites in degrees."""

from __future__ import annotations

import numpy as np
import pytest

from energy import Battery
from planner.cost_spec import CostSpec
from planner.tours import TourRobot, TourSearch, TourSites, plan_tour, read_tour_sites_csv
from terrain import DataError, InvalidParameterError, TerrainMap, UnknownNameError, flat_map
from terrain.georef import xy_to_lonlat


def test_a_site_off_the_map_or_on_an_obstacle_is_an_error_row_and_the_others_are_kept():
    obstacle = np.zeros((30, 30), bool)
    obstacle[10:14, 10:14] = True
    tmap = TerrainMap(np.zeros((30, 30)), 1.0, ground=np.zeros((30, 30), int), ground_names={0: "asphalt"},
                      obstacle=obstacle)
    cost = CostSpec().build(tmap)
    sites = TourSites(("ok", "off", "rock", "ok2"), [[5.0, 5.0], [45.0, 5.0], [11.5, 11.5], [20.0, 25.0]])
    res = plan_tour(cost, sites, TourRobot(Battery(1.0, 24.0), (2.0, 2.0)))
    assert set(res.errors) == {"off", "rock"}
    assert "off the map" in res.errors["off"] and "obstacle" in res.errors["rock"]
    assert set(res.visited) == {"ok", "ok2"}
    doc = res.to_dict()
    assert {e["site"] for e in doc["errors"]} == {"off", "rock"}


def test_bad_sites_raise_the_librarys_errors(tmp_path):
    with pytest.raises(InvalidParameterError, match="unique; 'a' appears 2 times"):
        TourSites(("a", "a"), [[1.0, 1.0], [2.0, 2.0]])
    with pytest.raises(InvalidParameterError, match="value must be >= 0 for every site; site 1 has -2.0"):
        TourSites(("a", "b"), [[1.0, 1.0], [2.0, 2.0]], value=[1.0, -2.0])
    with pytest.raises(InvalidParameterError, match="xy_m"):
        TourSites(("a",), [[np.nan, 1.0]])
    csv = tmp_path / "sites.csv"
    csv.write_text("name,x_m,y_m,value\na,1,1,1\na,2,2,1\n")
    with pytest.raises(DataError, match="used twice"):
        read_tour_sites_csv(csv)
    csv.write_text("name,x_m,y_m,value\na,1,1,-1\n")
    with pytest.raises(InvalidParameterError, match="value must be >= 0"):
        read_tour_sites_csv(csv)
    csv.write_text("name,x_m,y_m,value\na,1,1,lots\n")
    with pytest.raises(DataError, match="line 2: column 'value' is 'lots'"):
        read_tour_sites_csv(csv)
    cost = CostSpec().build(flat_map((20, 20), 1.0))
    with pytest.raises(InvalidParameterError, match="risk 0.2 lies below the median"):
        plan_tour(cost, TourSites(("a",), [[5.0, 5.0]]), TourRobot(Battery(1.0, 24.0), (2.0, 2.0)),
                  search=TourSearch(risk=0.2))
    twins = [TourRobot(Battery(1.0, 24.0), (2.0, 2.0), "r")] * 2
    with pytest.raises(InvalidParameterError, match="robot names must be unique; 'r' appears 2 times"):
        plan_tour(cost, TourSites(("a",), [[5.0, 5.0]]), twins)
    with pytest.raises(InvalidParameterError, match="needs? .*georeferenced|CRS"):
        TourSites.from_lonlat(("a",), [[10.0, 46.0]], flat_map((20, 20), 1.0))


def test_sites_in_degrees_are_placed_by_the_maps_crs(tmp_path):
    pytest.importorskip("rasterio", reason="degrees need the geo extra (rasterio's transforms)")
    tmap = flat_map((20, 20), 10.0, origin_xy_m=(500000.0, 5100000.0))
    tmap.crs = "EPSG:32632"
    xy = np.array([[500055.0, 5100045.0], [500120.0, 5100150.0]])
    lon, lat = xy_to_lonlat(xy[:, 0], xy[:, 1], tmap.crs)
    sites = TourSites.from_lonlat(("a", "b"), np.column_stack([lon, lat]), tmap, value=[1.0, 2.0])
    assert np.allclose(sites.xy_m, xy, atol=1e-3)
    csv = tmp_path / "sites.csv"
    csv.write_text("name,lon,lat,value\n" + "".join(f"{n},{x!r},{y!r},{v}\n" for n, x, y, v in
                                                     zip("ab", lon.tolist(), lat.tolist(), (1, 2))))
    read = read_tour_sites_csv(csv, tmap)
    assert read.names == ("a", "b") and np.allclose(read.xy_m, xy, atol=1e-3) and read.value.tolist() == [1.0, 2.0]


def test_the_search_and_the_fleet_are_checked_values():
    from planner.tours import TourFleet

    with pytest.raises(InvalidParameterError, match="risk"):
        TourSearch(risk=0.3)
    with pytest.raises(InvalidParameterError, match="time_limit_s must be > 0"):
        TourSearch(time_limit_s=0.0)
    with pytest.raises(UnknownNameError, match="solver must be one of"):
        TourSearch(solver="gurobi")
    with pytest.raises(InvalidParameterError, match=r"one per robot \(n_robots=3\), got 2 points") as err:
        TourFleet(battery=Battery(1.0, 24.0), depot_xy_m=[(1.0, 1.0), (2.0, 2.0)], n_robots=3)
    assert err.value.parameter == "depot_xy_m"
    assert TourFleet(battery=Battery(1.0, 24.0), depot_xy_m=(1, 2), n_robots=2).depot_xy_m == ((1.0, 2.0), (1.0, 2.0))
    with pytest.raises(InvalidParameterError, match="battery must be a Battery"):
        TourFleet(battery=1.0, depot_xy_m=(1, 2))
