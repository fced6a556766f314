"""Tests of terrain.vector: polygon rasterisation, grounds/obstacles from polygons, GeoJSON."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely
from shapely import LineString, MultiPolygon, Point, Polygon, box

from terrain import (
    FileFormatError,
    InvalidParameterError,
    TerrawattWarning,
    UnknownNameError,
    apply_geojson,
    flat_map,
    rasterize_polygons,
    read_geojson,
    set_ground_from_polygons,
    set_obstacles_from_polygons,
)


def write_json(path, obj):
    path.write_text(json.dumps(obj), encoding="utf-8")
    return path


def feature(geom, **props):
    return {"type": "Feature", "geometry": shapely.geometry.mapping(geom), "properties": props}


# --------------------------------------------------------------- rasterising
def test_box_covers_the_cells_whose_centres_it_holds(flat_map):
    # flat_map: 20 x 30 cells of 0.5 m; centres at 0.25, 0.75, ...
    mask = rasterize_polygons(flat_map, box(1.0, 2.0, 2.0, 3.5))
    expected = np.zeros(flat_map.shape, bool)
    expected[4:7, 2:4] = True
    np.testing.assert_array_equal(mask, expected)
    assert mask.dtype == bool


def test_centres_on_the_boundary_count_as_inside(flat_map):
    mask = rasterize_polygons(flat_map, box(0.25, 0.25, 0.75, 0.75))
    assert mask.sum() == 4 and mask[:2, :2].all()


def test_matches_a_per_cell_reference():
    tmap = flat_map((23, 31), 0.37, origin_xy_m=(3.0, -2.0))
    rng = np.random.default_rng(0)
    centres, radii = rng.uniform([3, -2], [14, 6], (6, 2)), rng.uniform(0.5, 2, 6)
    blob = shapely.union_all(shapely.buffer(shapely.points(centres), radii))
    holey = Polygon([(5, -1), (12, -1), (12, 5), (5, 5)], [[(7, 1), (10, 1), (10, 3), (7, 3)]])
    xs, ys = tmap.cell_centres()
    for geom in (blob, holey):
        expected = np.array([[geom.intersects(Point(x, y)) for x in xs] for y in ys])
        np.testing.assert_array_equal(rasterize_polygons(tmap, geom), expected)
    assert not rasterize_polygons(tmap, holey)[tmap.rowcol(8.5, 2.0)]


def test_later_geometries_win_and_values_fill_dtype(flat_map):
    geoms = [box(0, 0, 15, 10), box(5, 0, 15, 10)]
    out = rasterize_polygons(flat_map, geoms, [2, 9], fill=-1, dtype=np.int16)
    assert out.dtype == np.int16
    assert set(np.unique(out[:, :10]).tolist()) == {2} and set(np.unique(out[:, 10:]).tolist()) == {9}
    part = rasterize_polygons(flat_map, box(0, 0, 1, 1), 2.5, fill=np.nan)
    assert np.isnan(part).sum() == part.size - 4 and part[0, 0] == 2.5


def test_multipolygon(flat_map):
    multi = MultiPolygon([box(0, 0, 1, 1), box(10, 5, 11, 6)])
    mask = rasterize_polygons(flat_map, multi)
    assert mask.sum() == 8 and mask[0, 0] and mask[10, 20]


def test_user_geometry_is_not_left_prepared(flat_map):
    geom = box(0, 0, 2, 2)
    rasterize_polygons(flat_map, geom)
    assert not shapely.is_prepared(geom)


def test_geometry_outside_the_map_warns(flat_map):
    with pytest.warns(TerrawattWarning, match="1 of 2 geometries cover no cell centre"):
        mask = rasterize_polygons(flat_map, [box(0, 0, 1, 1), box(100, 100, 101, 101)])
    assert mask.sum() == 4


@pytest.mark.parametrize(
    ("geoms", "match"),
    [
        (LineString([(0, 0), (5, 5)]), r"geoms\[0\] is a LineString; expected a Polygon.*buffer"),
        (Point(1, 1), r"geoms\[0\] is a Point"),
        ([box(0, 0, 1, 1), "box"], r"geoms\[1\] is a str"),
        (Polygon([(0, 0), (4, 4), (4, 0), (0, 4)]), r"geoms\[0\] is not a valid polygon \(Self-intersection"),
        (3, "must be a shapely"),
    ],
)
def test_bad_geometries_raise(flat_map, geoms, match):
    with pytest.raises(InvalidParameterError, match=match):
        rasterize_polygons(flat_map, geoms)


def test_bad_values_raise(flat_map):
    with pytest.raises(InvalidParameterError, match=r"one entry per geometry \(2\)"):
        rasterize_polygons(flat_map, [box(0, 0, 1, 1), box(1, 1, 2, 2)], [1, 2, 3])
    with pytest.raises(InvalidParameterError, match="numbers or booleans"):
        rasterize_polygons(flat_map, box(0, 0, 1, 1), "sand")


# --------------------------------------------------- grounds and obstacles
def test_set_ground_adds_new_names_and_keeps_the_rest(flat_map):
    polygons = {
        "sand": box(0, 0, 5, 10),
        "asphalt": box(0, 0, 1, 10),
        "snow": [box(10, 0, 11, 1), box(14, 9, 15, 10)],
    }
    out = set_ground_from_polygons(flat_map, polygons)
    assert out.ground_names == {0: "asphalt", 1: "sand", 2: "snow"}
    assert np.all(out.ground[:, :2] == 0) and np.all(out.ground[:, 2:10] == 1)
    assert np.all(out.ground[:, 10:20] == 0)
    assert (out.ground == 2).sum() == 8
    # the input map is untouched
    assert flat_map.ground_names == {0: "asphalt"} and np.all(flat_map.ground == 0)


def test_set_ground_unknown_name_when_adding_is_off(flat_map):
    with pytest.raises(UnknownNameError, match=r"'lava' is not one of the map's grounds \['asphalt'\]"):
        set_ground_from_polygons(flat_map, {"lava": box(0, 0, 1, 1)}, add_names=False)
    same = set_ground_from_polygons(flat_map, {"asphalt": box(0, 0, 1, 1)}, add_names=False)
    assert same.ground_names == {0: "asphalt"}


def test_set_ground_argument_errors(flat_map):
    with pytest.raises(InvalidParameterError, match="must map ground names to polygons"):
        set_ground_from_polygons(flat_map, [box(0, 0, 1, 1)])
    with pytest.raises(InvalidParameterError, match="non-empty strings"):
        set_ground_from_polygons(flat_map, {"": box(0, 0, 1, 1)})
    with pytest.raises(InvalidParameterError, match=r"polygons\['sand'\]\[0\] is a LineString"):
        set_ground_from_polygons(flat_map, {"sand": LineString([(0, 0), (1, 1)])})


def test_set_obstacles_adds_or_replaces(wall_map):
    rock = Point(5.5, 5.5).buffer(1.1)
    added = set_obstacles_from_polygons(wall_map, rock)
    assert added.obstacle.sum() == wall_map.obstacle.sum() + 5 and added.obstacle[:, 20].sum() == 36
    replaced = set_obstacles_from_polygons(wall_map, [rock], replace=True)
    assert replaced.obstacle.sum() == 5 and not replaced.obstacle[:, 20].any()
    assert wall_map.obstacle.sum() == 36  # input untouched


# ------------------------------------------------------------------- GeoJSON
def test_read_geojson_feature_collection(tmp_path):
    path = write_json(
        tmp_path / "a.geojson",
        {
            "type": "FeatureCollection",
            "features": [
                feature(box(0, 0, 1, 1), ground="sand"),
                {**feature(box(2, 2, 3, 3)), "properties": None},
            ],
        },
    )
    items = read_geojson(path)
    assert [props for _, props in items] == [{"ground": "sand"}, {}]
    assert items[0][0].equals(box(0, 0, 1, 1))


def test_read_geojson_single_feature_and_bare_geometry(tmp_path):
    one = read_geojson(write_json(tmp_path / "f.json", feature(box(0, 0, 2, 1), obstacle=True)))
    assert len(one) == 1 and one[0][1] == {"obstacle": True} and one[0][0].area == 2.0
    bare = read_geojson(write_json(tmp_path / "g.json", shapely.geometry.mapping(box(0, 0, 3, 1))))
    assert len(bare) == 1 and bare[0][1] == {} and bare[0][0].area == 3.0


@pytest.mark.parametrize(
    ("content", "match"),
    [
        ("{not json", "not a readable JSON file"),
        ("[" * 100_000, "not a readable JSON file.*RecursionError"),
        ('{"type": "Feature", "n": ' + "9" * 5000 + "}", "not a readable JSON file.*4300 digits"),
        ("[1, 2]", "not GeoJSON"),
        ('{"type": "FeatureCollection"}', "needs a 'features' list"),
        (
            '{"type": "FeatureCollection", "features": [{"type": "Point"}]}',
            "feature 0: expected an object with type 'Feature'",
        ),
        ('{"type": "Feature", "geometry": null, "properties": {}}', "feature 0: needs a geometry"),
        (
            '{"type": "Feature", "geometry": {"type": "Polygon", "coordinates": "x"}}',
            "feature 0: invalid geometry",
        ),
        (
            json.dumps(feature(Polygon([(0, 0), (4, 4), (4, 0), (0, 4)]))),
            r"feature 0: invalid geometry \(Self-intersection",
        ),
    ],
)
def test_read_geojson_bad_files(tmp_path, content, match):
    path = tmp_path / "bad.geojson"
    path.write_text(content, encoding="utf-8")
    with pytest.raises(FileFormatError, match=match):
        read_geojson(path)


def test_read_geojson_missing_file(tmp_path):
    with pytest.raises(FileFormatError, match="does not exist"):
        read_geojson(tmp_path / "none.geojson")


def test_apply_geojson_sets_grounds_and_obstacles(tmp_path, flat_map):
    collection = {
        "type": "FeatureCollection",
        "features": [
            feature(box(0, 0, 5, 10), ground="grass"),
            feature(box(4, 0, 5, 10), ground="sand", obstacle=True),
            feature(Point(12.0, 5.0).buffer(0.6), obstacle=True),
        ],
    }
    out = apply_geojson(flat_map, write_json(tmp_path / "m.geojson", collection))
    assert out.ground_names == {0: "asphalt", 1: "grass", 2: "sand"}
    assert np.all(out.ground[:, :8] == 1) and np.all(out.ground[:, 8:10] == 2)
    assert np.all(out.ground[:, 10:] == 0)
    assert out.obstacle[:, 8:10].all() and out.obstacle.sum() == 40 + 4
    # the same from already-read features
    again = apply_geojson(flat_map, read_geojson(tmp_path / "m.geojson"))
    np.testing.assert_array_equal(again.ground, out.ground)
    assert not flat_map.obstacle.any()


@pytest.mark.parametrize(
    ("props", "geom", "match"),
    [
        ({"name": "field"}, box(0, 0, 1, 1), "feature 0 has neither a 'ground' name nor 'obstacle': true"),
        ({"obstacle": False}, box(0, 0, 1, 1), "feature 0 has neither"),
        ({"obstacle": "yes"}, box(0, 0, 1, 1), "'obstacle' must be true or false, got 'yes'"),
        ({"ground": 3}, box(0, 0, 1, 1), "'ground' must be a non-empty string, got 3"),
        ({"obstacle": True}, LineString([(0, 0), (1, 1)]), "feature 0 is a LineString"),
    ],
)
def test_apply_geojson_bad_features(tmp_path, flat_map, props, geom, match):
    collection = {"type": "FeatureCollection", "features": [feature(geom, **props)]}
    path = write_json(tmp_path / "m.geojson", collection)
    with pytest.raises(FileFormatError, match=match):
        apply_geojson(flat_map, path)


def test_apply_geojson_unknown_ground_when_adding_is_off(flat_map):
    with pytest.raises(UnknownNameError, match="'lava'"):
        apply_geojson(flat_map, [(box(0, 0, 1, 1), {"ground": "lava"})], add_names=False)


def test_apply_geojson_custom_keys(flat_map):
    out = apply_geojson(flat_map, [(box(0, 0, 1, 1), {"surface": "sand"})], ground_key="surface")
    assert out.ground_names[1] == "sand" and (out.ground == 1).sum() == 4

