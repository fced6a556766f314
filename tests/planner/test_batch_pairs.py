"""Pairs and sites files in WGS 84 degrees (planner.batch_pairs); the metre files are tested in test_batch.py."""

from __future__ import annotations

import numpy as np
import pytest

from planner import read_pairs_csv
from planner.batch_pairs import read_sites_csv
from terrain import DataError, FileFormatError, InvalidParameterError, TerrainMap, lonlat_to_xy

pytest.importorskip("rasterio")


@pytest.fixture
def utm_map() -> TerrainMap:
    return TerrainMap(np.zeros((4, 4)), 30.0, (500_000.0, 4_982_900.0), crs="EPSG:32633")


def _write(path, text):
    path.write_text(text)
    return path


def test_pairs_in_degrees_are_placed_in_the_maps_metres(tmp_path, utm_map):
    f = _write(tmp_path / "p.csv", "name,start_lon,start_lat,goal_lon,goal_lat\nthere,15.0,45.0,15.001,45.0005\n"
                                   "far,15.0,45.0,16.0,45.0\n")
    pairs = read_pairs_csv(f, utm_map)
    assert pairs.names == ("there", "far")
    assert pairs.starts_xy_m[0] == pytest.approx(lonlat_to_xy(15.0, 45.0, "EPSG:32633"))
    assert pairs.goals_xy_m[0] == pytest.approx(lonlat_to_xy(15.001, 45.0005, "EPSG:32633"))
    assert not utm_map.contains(*pairs.goals_xy_m[1])  # read as it is: planning makes it an error row


def test_sites_in_degrees(tmp_path, utm_map):
    names, xy = read_sites_csv(_write(tmp_path / "s.csv", "lon,lat\n15.0,45.0\n15.001,45.0005\n"), utm_map)
    assert names == ("0", "1")
    assert xy[1] == pytest.approx(lonlat_to_xy(15.001, 45.0005, "EPSG:32633"))


@pytest.mark.parametrize(
    ("text", "where", "error", "match"),
    [
        ("start_lon,start_lat,goal_lon,goal_lat\n15,45,15,45.1\n", None, InvalidParameterError,
         "gives longitude / latitude; pass where=<the georeferenced map>"),
        ("start_lon,start_lat,goal_lon,goal_lat\n15,45,15,45.1\n", TerrainMap(np.zeros((2, 2)), 1.0),
         InvalidParameterError, "has no CRS"),
        ("start_lon,start_lat,goal_lon,goal_lat\n15,45,15,95\n", "map", DataError,
         r"line 2: column 'goal_lat' is '95'; expected degrees in \[-90, 90\]"),
        ("start_lon,start_lat,goal_lon,goal_lat\n15,45,east,45\n", "map", DataError,
         r"line 2: column 'goal_lon' is 'east'; expected a finite number of degrees"),
        ("start_x_m,start_y_m,goal_x_m,goal_y_m,start_lon,start_lat,goal_lon,goal_lat\n1,2,3,4,15,45,15,45\n", "map",
         FileFormatError, "has both the columns"),
        ("start_lon,start_lat,goal_lon\n15,45,15\n", "map", FileFormatError,
         r"lacks the column\(s\) \['start_x_m', 'start_y_m', 'goal_x_m', 'goal_y_m'\]; .*, or \['start_lon', "
         r"'start_lat', 'goal_lon', 'goal_lat'\] \(degrees\)"),
    ],
)
def test_bad_pairs_in_degrees_are_refused(tmp_path, utm_map, text, where, error, match):
    with pytest.raises(error, match=match):
        read_pairs_csv(_write(tmp_path / "p.csv", text), utm_map if where == "map" else where)
