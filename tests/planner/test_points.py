"""Points in metres and in WGS 84 longitude / latitude (planner.points)."""

from __future__ import annotations

import numpy as np
import pytest

from planner.points import lonlat_points
from terrain import InvalidParameterError, OutOfBoundsError, TerrainMap

pytest.importorskip("rasterio")


@pytest.fixture
def utm_map() -> TerrainMap:
    """4 x 4 cells of 30 m whose south-west corner is 50 m south of (15 E, 45 N), in UTM zone 33."""
    return TerrainMap(np.zeros((4, 4)), 30.0, (500_000.0, 4_982_900.0), crs="EPSG:32633")


def test_lon_lat_points_are_the_maps_metres(utm_map):
    xy = lonlat_points([(15.0, 45.0), (15.001, 45.0005)], utm_map, "starts")
    assert xy.shape == (2, 2)
    assert xy[0] == pytest.approx((500_000.0, 4_982_950.4), abs=0.1)
    assert utm_map.contains(xy[1, 0], xy[1, 1])


def test_a_point_off_the_map_is_named_in_both_forms(utm_map):
    message = (r"--goal-lonlat \(lon 15\.1, lat 45\) is \(507881\.\d+, 4982955\.\d+\) m in the map's CRS EPSG:32633, "
               r"outside the map bounds \(500000, 4982900, 500120, 4983020\) m, which span lon 15 to 15\.0015\d*, "
               r"lat 44\.9995\d* to 45\.0006\d*")
    with pytest.raises(OutOfBoundsError, match=message):
        lonlat_points((15.1, 45.0), utm_map, "--goal-lonlat")


def test_lon_lat_on_a_map_without_crs_is_refused():
    with pytest.raises(InvalidParameterError, match="has no CRS"):
        lonlat_points((15.0, 45.0), TerrainMap(np.zeros((2, 2)), 1.0), "start")


def test_bad_shapes_are_refused(utm_map):
    with pytest.raises(InvalidParameterError, match=r"start must have shape \(N, 2\) \(lon_deg, lat_deg\)"):
        lonlat_points((15.0, 45.0, 3.0), utm_map, "start")


def test_point_on_map_takes_metres_or_degrees_and_names_them(utm_map):
    from planner.points import point_on_map

    assert point_on_map(None, None, utm_map) is None
    assert point_on_map([500010, 4982910], None, utm_map) == (500010.0, 4982910.0)
    x, y = point_on_map(None, (15.0, 45.0), utm_map)
    np.testing.assert_allclose([x, y], lonlat_points((15.0, 45.0), utm_map, "p")[0])
    with pytest.raises(InvalidParameterError, match=r"^depot must be two finite coordinates \(m\), got \[nan, 5.0\]") as bad:
        point_on_map([float("nan"), 5.0], None, utm_map, names=("depot", "depot_lonlat"))
    assert bad.value.parameter == "depot"  # the caller's parameter: a front end says it its own way
    with pytest.raises(InvalidParameterError, match="give xy_m or lonlat, not both") as both:
        point_on_map((1.0, 2.0), (15.0, 45.0), utm_map)
    assert both.value.parameter == ("xy_m", "lonlat")
    with pytest.raises(OutOfBoundsError, match="^goal_lonlat") as off:
        point_on_map(None, (16.0, 45.0), utm_map, names=("goal", "goal_lonlat"))
    assert off.value.parameter == "goal_lonlat"
