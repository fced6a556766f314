"""Tests of terrain.terrain_map: TerrainMap construction, coordinates, derived layers, sampling, I/O."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from terrain import (
    MAP_FORMAT_VERSION,
    UNKNOWN_GROUND,
    FileFormatError,
    FormatVersionError,
    GridMismatchError,
    InvalidParameterError,
    OutOfBoundsError,
    TerrainMap,
    UnknownNameError,
)


def plane_map(a: float, b: float, c: float = 3.0, shape=(6, 9), cell_size_m=0.25, origin=(100.0, -40.0)):
    """Map of the plane z = a*(x - x0) + b*(y - y0) + c sampled at cell centres."""
    rows, cols = shape
    x = (np.arange(cols) + 0.5) * cell_size_m
    y = (np.arange(rows) + 0.5) * cell_size_m
    z = a * x[None, :] + b * y[:, None] + c
    return TerrainMap(z, cell_size_m, origin)


# ---------------------------------------------------------------- construction
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_elevation_raises(bad):
    z = np.zeros((3, 4))
    z[1, 2] = bad
    with pytest.raises(InvalidParameterError, match="1 NaN/inf cells"):
        TerrainMap(z, 1.0)


@pytest.mark.parametrize("shape", [(5,), (1, 5), (5, 1), (2, 2, 2), ()])
def test_elevation_must_be_2d_and_at_least_2x2(shape):
    with pytest.raises(InvalidParameterError, match="2-D array of at least 2 x 2"):
        TerrainMap(np.zeros(shape), 1.0)


@pytest.mark.parametrize("cell", [0.0, -1.0, np.nan, np.inf])
def test_cell_size_must_be_positive_and_finite(cell):
    with pytest.raises(InvalidParameterError, match="cell_size_m must be (finite|> 0)"):
        TerrainMap(np.zeros((3, 3)), cell)


def test_origin_must_be_finite():
    with pytest.raises(InvalidParameterError, match=r"origin_xy_m\[0\] must be finite"):
        TerrainMap(np.zeros((3, 3)), 1.0, (np.nan, 0.0))


@pytest.mark.parametrize("layer", ["ground", "obstacle"])
def test_layer_of_other_shape_raises(layer):
    with pytest.raises(GridMismatchError, match=rf"layer '{layer}' has shape \(3, 5\).*\(3, 4\)"):
        TerrainMap(np.zeros((3, 4)), 1.0, **{layer: np.zeros((3, 5), int)})


def test_extra_layer_of_other_shape_raises(flat_map):
    with pytest.raises(GridMismatchError, match="layer 'cost'"):
        flat_map["cost"] = np.zeros((2, 2))


def test_unknown_ground_class_id_raises():
    ground = np.array([[0, 1], [2, -1]])
    with pytest.raises(UnknownNameError, match=r"class ids \[2\] with no name"):
        TerrainMap(np.zeros((2, 2)), 1.0, ground=ground, ground_names={0: "grass", 1: "sand"})


@pytest.mark.parametrize("bad_id", [65535, 65536, 40000, -2])
def test_ground_ids_outside_the_int16_range_raise_instead_of_wrapping(bad_id):
    # 65535 would wrap to -1 (unknown) and 65536 to 0 (a named class) in an int16 layer
    ground = np.array([[0, 0], [0, bad_id]])
    with pytest.raises(InvalidParameterError, match=rf"class ids in \[{min(0, bad_id)}, {max(0, bad_id)}\]"):
        TerrainMap(np.zeros((2, 2)), 1.0, ground=ground, ground_names={0: "grass"})


def test_ground_must_hold_integers():
    with pytest.raises(InvalidParameterError, match="integer class ids"):
        TerrainMap(np.zeros((2, 2)), 1.0, ground=np.full((2, 2), 0.5), ground_names={0: "grass"})


def test_obstacle_must_be_boolean():
    with pytest.raises(InvalidParameterError, match="obstacle layer must be boolean"):
        TerrainMap(np.zeros((2, 2)), 1.0, obstacle=np.array([[0, 2], [1, 0]]))


@pytest.mark.parametrize(
    ("names", "match"),
    [
        ({-2: "x"}, "ground class id must be >= 0"),
        ({40000: "x"}, "ground class id must be <= 32767"),
        ({"a": "x"}, "ground class id must be an integer, got 'a'"),
        ([(0, "x")], "ground_names must be a mapping"),
        ({0: ""}, "non-empty name"),
        ({0: "a", 1: "a"}, "unique"),
    ],
)
def test_bad_ground_names_raise(names, match):
    with pytest.raises(InvalidParameterError, match=match):
        TerrainMap(np.zeros((2, 2)), 1.0, ground_names=names)


def test_renaming_grounds_must_keep_every_used_id(flat_map):
    with pytest.raises(UnknownNameError, match=r"class ids \[0\]"):
        flat_map.ground_names = {1: "grass"}
    assert flat_map.ground_names == {0: "asphalt"}


def test_defaults_unknown_ground_and_no_obstacles():
    tmap = TerrainMap(np.zeros((3, 4)), 2.0)
    assert tmap.ground.dtype == np.int16 and np.all(tmap.ground == UNKNOWN_GROUND)
    assert tmap.obstacle.dtype == bool and not tmap.obstacle.any()
    assert tmap.keys() == ["elevation", "ground", "obstacle"]


def test_ground_id_and_unknown_name(flat_map):
    assert flat_map.ground_id("asphalt") == 0
    with pytest.raises(UnknownNameError, match="no ground class named 'lava'"):
        flat_map.ground_id("lava")


# --------------------------------------------------------------- layers (dict)
def test_layers_are_read_only(flat_map):
    for name in ("elevation", "ground", "obstacle", "slope", "grad_x"):
        with pytest.raises(ValueError, match="read-only"):
            flat_map[name][0, 0] = 1


def test_setting_layer_copies_the_input(flat_map):
    cost = np.ones(flat_map.shape)
    flat_map["cost"] = cost
    cost[0, 0] = 99.0
    assert flat_map["cost"][0, 0] == 1.0
    assert "cost" in flat_map and len(flat_map) == 4 and list(flat_map) == flat_map.keys()


def test_derived_layers_cannot_be_set_and_follow_elevation(flat_map):
    with pytest.raises(InvalidParameterError, match="derived from elevation"):
        flat_map["slope"] = np.zeros(flat_map.shape)
    assert flat_map.slope_rad.max() == 0.0
    x, _ = np.meshgrid(*flat_map.cell_centres())
    flat_map["elevation"] = 0.3 * x
    np.testing.assert_allclose(flat_map["grad_x"], 0.3, rtol=1e-12)


def test_unknown_layer_and_deleting(flat_map):
    with pytest.raises(UnknownNameError, match="no layer named 'nope'"):
        flat_map["nope"]
    with pytest.raises(InvalidParameterError, match="cannot be removed"):
        del flat_map["elevation"]
    with pytest.raises(UnknownNameError, match="no layer named 'nope'"):
        del flat_map["nope"]
    flat_map["cost"] = np.zeros(flat_map.shape)
    del flat_map["cost"]
    assert "cost" not in flat_map


def test_copy_is_independent(ramp_map):
    dup = ramp_map.copy()
    dup["obstacle"] = np.ones(dup.shape, bool)
    dup.ground_names = {0: "asphalt", 1: "sand"}
    assert not ramp_map.obstacle.any() and ramp_map.ground_names == {0: "asphalt"}
    assert dup.same_grid(ramp_map)
    np.testing.assert_array_equal(dup.elevation_m, ramp_map.elevation_m)


# ----------------------------------------------------------------- coordinates
def test_bounds_and_from_bounds():
    tmap = TerrainMap(np.zeros((4, 6)), 0.5, (-1.0, 2.0))
    assert tmap.bounds == (-1.0, 2.0, 2.0, 4.0)
    same = TerrainMap.from_bounds(np.zeros((4, 6)), (-1.0, 2.0, 2.0, 4.0))
    assert same.same_grid(tmap)
    with pytest.raises(InvalidParameterError, match="square cells"):
        TerrainMap.from_bounds(np.zeros((4, 6)), (0.0, 0.0, 6.0, 8.0))


def test_rowcol_xy_round_trip_with_offset_origin_and_non_unit_cells():
    tmap = TerrainMap(np.zeros((7, 11)), 0.3, (1000.0, -50.0))
    rows, cols = np.meshgrid(np.arange(7), np.arange(11), indexing="ij")
    x, y = tmap.xy(rows, cols)
    np.testing.assert_allclose(x[0, :3], 1000.0 + np.array([0.15, 0.45, 0.75]))
    np.testing.assert_allclose(y[:3, 0], -50.0 + np.array([0.15, 0.45, 0.75]))
    back_r, back_c = tmap.rowcol(x, y)
    np.testing.assert_array_equal(back_r, rows)
    np.testing.assert_array_equal(back_c, cols)


def test_rowcol_row_grows_with_y_and_far_edges_map_inside():
    tmap = TerrainMap(np.zeros((4, 5)), 2.0, (10.0, 20.0))
    assert tmap.rowcol(10.0, 20.0) == (0, 0)
    assert tmap.rowcol(10.0, 22.0) == (1, 0)
    assert tmap.rowcol(20.0, 28.0) == (3, 4)  # upper-right corner belongs to the last cell


def test_rowcol_and_xy_broadcast_scalars_against_arrays():
    tmap = TerrainMap(np.zeros((4, 5)), 1.0)
    rows, cols = tmap.rowcol(np.array([0.5, 3.5]), 2.5)
    assert rows.tolist() == [2, 2] and cols.tolist() == [0, 3]
    x, y = tmap.xy(np.array([0, 3]), 1)
    assert x.tolist() == [1.5, 1.5] and y.tolist() == [0.5, 3.5]


@pytest.mark.parametrize(("x", "y"), [(-0.01, 1.0), (5.01, 1.0), (1.0, 4.5), (np.nan, 1.0)])
def test_rowcol_outside_raises(x, y):
    tmap = TerrainMap(np.zeros((4, 5)), 1.0)
    with pytest.raises(OutOfBoundsError, match="outside the map bounds"):
        tmap.rowcol(np.array([1.0, x]), np.array([1.0, y]))
    assert not tmap.contains(x, y)


# ------------------------------------------------------------- slope / aspect
@pytest.mark.parametrize(
    ("a", "b", "aspect"),
    [(0.2, 0.0, np.pi), (-0.2, 0.0, 0.0), (0.0, 0.2, -np.pi / 2), (0.0, -0.2, np.pi / 2)],
)
def test_slope_and_aspect_of_axis_ramps(a, b, aspect):
    tmap = plane_map(a, b)  # non-unit cells (0.25 m) catch spacing bugs
    np.testing.assert_allclose(tmap.slope_rad, np.arctan(0.2), rtol=1e-12)
    np.testing.assert_allclose(np.cos(tmap.aspect_rad), np.cos(aspect), atol=1e-12)
    np.testing.assert_allclose(np.sin(tmap.aspect_rad), np.sin(aspect), atol=1e-12)


def test_gradients_of_an_oblique_plane():
    tmap = plane_map(0.12, -0.05, cell_size_m=2.5)
    np.testing.assert_allclose(tmap["grad_x"], 0.12, rtol=1e-12)
    np.testing.assert_allclose(tmap["grad_y"], -0.05, rtol=1e-12)
    np.testing.assert_allclose(tmap.slope_rad, np.arctan(np.hypot(0.12, 0.05)), rtol=1e-12)
    # aspect points downhill: against the gradient
    np.testing.assert_allclose(tmap.aspect_rad, np.arctan2(0.05, -0.12), rtol=1e-12)


def test_ramp_fixture_has_the_documented_grade(ramp_map, ramp_grade):
    np.testing.assert_allclose(ramp_map["grad_x"], ramp_grade, rtol=1e-12)
    np.testing.assert_allclose(ramp_map["grad_y"], 0.0, atol=1e-15)


# ------------------------------------------------------------------ sampling
def test_bilinear_sample_of_a_plane_is_exact_inside_the_centres():
    tmap = plane_map(0.3, -0.7, c=2.0)
    rng = np.random.default_rng(0)
    xs, ys = tmap.cell_centres()
    x = rng.uniform(xs[0], xs[-1], 200)
    y = rng.uniform(ys[0], ys[-1], 200)
    x0, y0 = tmap.origin_xy_m
    expected = 0.3 * (x - x0) - 0.7 * (y - y0) + 2.0
    np.testing.assert_allclose(tmap.sample("elevation", x, y, "bilinear"), expected, rtol=1e-12)
    assert isinstance(tmap.sample("elevation", x[0], y[0], "bilinear"), float)


def test_bilinear_clamps_outside_the_outer_centres_and_nearest_takes_the_cell():
    tmap = plane_map(1.0, 0.0, c=0.0, cell_size_m=1.0, origin=(0.0, 0.0))
    # left edge x = 0 lies half a cell outside the first centre (value 0.5)
    assert tmap.sample("elevation", 0.0, 2.0, "bilinear") == pytest.approx(0.5)
    assert tmap.sample("elevation", 3.9, 2.0, "nearest") == pytest.approx(3.5)


def test_sample_errors():
    tmap = plane_map(1.0, 0.0)
    x, y = tmap.cell_centres()
    with pytest.raises(UnknownNameError, match="method must be 'nearest' or 'bilinear'"):
        tmap.sample("elevation", x[0], y[0], "cubic")
    with pytest.raises(OutOfBoundsError):
        tmap.sample("elevation", x[0] - 10.0, y[0], "bilinear")


# ------------------------------------------------------------- segment cells
def test_segment_through_cell_corners():
    tmap = TerrainMap(np.zeros((3, 3)), 1.0)
    rows, cols, lengths = tmap.segment_cells((0.5, 0.5), (2.5, 2.5))
    assert rows.tolist() == [0, 1, 2] and cols.tolist() == [0, 1, 2]
    np.testing.assert_allclose(lengths, np.sqrt(2) * np.array([0.5, 1.0, 0.5]))


def test_zero_length_segment_is_one_cell_of_length_zero():
    tmap = TerrainMap(np.zeros((3, 3)), 2.0)
    rows, cols, lengths = tmap.segment_cells((3.0, 1.0), (3.0, 1.0))
    assert rows.tolist() == [0] and cols.tolist() == [1] and lengths.tolist() == [0.0]


def test_segment_outside_raises():
    tmap = TerrainMap(np.zeros((3, 3)), 1.0)
    with pytest.raises(OutOfBoundsError):
        tmap.segment_cells((0.5, 0.5), (3.5, 0.5))


def test_sample_segment_on_a_ramp(ramp_map, ramp_grade):
    values, lengths = ramp_map.sample_segment("elevation", (0.25, 1.0), (19.75, 1.0))
    x, _ = ramp_map.cell_centres()
    np.testing.assert_allclose(values, ramp_grade * x)
    assert lengths.sum() == pytest.approx(19.5)


_COORD = st.floats(0.0, 1.0, allow_nan=False)


@settings(max_examples=150, deadline=None)
@given(ax=_COORD, ay=_COORD, bx=_COORD, by=_COORD)
def test_segment_lengths_sum_to_segment_length(ax, ay, bx, by):
    tmap = TerrainMap(np.zeros((9, 13)), 0.7, (-3.0, 5.0))
    xmin, ymin, xmax, ymax = tmap.bounds
    a = (xmin + ax * (xmax - xmin), ymin + ay * (ymax - ymin))
    b = (xmin + bx * (xmax - xmin), ymin + by * (ymax - ymin))
    rows, cols, lengths = tmap.segment_cells(a, b)
    assert lengths.sum() == pytest.approx(np.hypot(b[0] - a[0], b[1] - a[1]), rel=1e-9, abs=1e-12)
    assert np.all(lengths >= 0) and np.all(lengths <= np.sqrt(2) * 0.7 * (1 + 1e-9))
    # consecutive cells are distinct 8-neighbours: the traversal skips no cell
    steps = np.abs(np.diff(np.stack([rows, cols]), axis=1))
    assert np.all(steps.max(axis=0) == 1)


# ---------------------------------------------------------------- persistence
def test_save_load_round_trip(tmp_path):
    rng = np.random.default_rng(1)
    tmap = TerrainMap(
        rng.normal(size=(5, 7)),
        0.4,
        (12.5, -3.0),
        ground=rng.integers(-1, 3, size=(5, 7)),
        ground_names={0: "grass", 1: "sand", 2: "snow"},
        obstacle=rng.random((5, 7)) < 0.3,
        crs="EPSG:32633",
    )
    tmap["cost"] = rng.random((5, 7))
    tmap["visits"] = rng.integers(0, 9, size=(5, 7)).astype(np.int32)
    back = TerrainMap.load(tmap.save(tmp_path / "sub" / "m.npz"))
    assert back.same_grid(tmap) and back.crs == "EPSG:32633"
    assert back.ground_names == tmap.ground_names and back.keys() == tmap.keys()
    for name in tmap:
        np.testing.assert_array_equal(back[name], tmap[name])
        assert back[name].dtype == tmap[name].dtype


def test_save_without_crs_loads_none(tmp_path, flat_map):
    assert TerrainMap.load(flat_map.save(tmp_path / "m.npz")).crs is None


def test_save_needs_npz_suffix(tmp_path, flat_map):
    with pytest.raises(InvalidParameterError, match="end in '.npz'"):
        flat_map.save(tmp_path / "m.npy")


def test_atomic_save_leaves_only_the_file(tmp_path, flat_map):
    path = flat_map.save(tmp_path / "m.npz")
    flat_map.save(path)  # overwrite
    assert os.listdir(tmp_path) == ["m.npz"]


def test_failed_save_keeps_the_old_file_and_no_temp(tmp_path, flat_map, ramp_map, monkeypatch):
    path = flat_map.save(tmp_path / "m.npz")

    def fail(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez_compressed", fail)
    with pytest.raises(OSError, match="disk full"):
        ramp_map.save(path)
    monkeypatch.undo()
    assert os.listdir(tmp_path) == ["m.npz"]
    assert TerrainMap.load(path).shape == flat_map.shape


def test_load_missing_file(tmp_path):
    with pytest.raises(FileFormatError, match="does not exist"):
        TerrainMap.load(tmp_path / "none.npz")


@pytest.mark.parametrize("cut", [0.5, 0.9])
def test_load_truncated_file(tmp_path, ramp_map, cut):
    path = ramp_map.save(tmp_path / "m.npz")
    data = path.read_bytes()
    path.write_bytes(data[: int(cut * len(data))])
    with pytest.raises(FileFormatError, match="corrupt or not a .npz"):
        TerrainMap.load(path)


def test_load_file_with_flipped_bytes(tmp_path):
    rng = np.random.default_rng(2)
    path = TerrainMap(rng.normal(size=(40, 40)), 1.0).save(tmp_path / "m.npz")
    data = bytearray(path.read_bytes())
    data[len(data) // 3 : len(data) // 3 + 64] = bytes(64)
    path.write_bytes(bytes(data))
    with pytest.raises(FileFormatError, match="corrupt"):
        TerrainMap.load(path)


def test_load_garbage_and_npy_files(tmp_path):
    garbage = tmp_path / "g.npz"
    garbage.write_bytes(b"not a zip at all")
    with pytest.raises(FileFormatError, match="corrupt or not a .npz"):
        TerrainMap.load(garbage)
    npy = tmp_path / "a.npy"
    np.save(npy, np.zeros(3))
    with pytest.raises(FileFormatError, match="corrupt or not a .npz"):
        TerrainMap.load(npy)


def test_load_foreign_npz(tmp_path):
    path = tmp_path / "other.npz"
    np.savez(path, a=np.zeros(3))
    with pytest.raises(FileFormatError, match="not a terrawatt map"):
        TerrainMap.load(path)


def test_load_other_format_version(tmp_path, flat_map):
    path = flat_map.save(tmp_path / "m.npz")
    with np.load(path) as data:
        content = dict(data)
    content["__version__"] = np.array(MAP_FORMAT_VERSION + 98)
    np.savez_compressed(path, **content)
    with pytest.raises(FormatVersionError, match=f"format version {MAP_FORMAT_VERSION + 98}"):
        TerrainMap.load(path)


def test_load_terrawatt_file_missing_entries(tmp_path):
    path = tmp_path / "m.npz"
    np.savez(path, __magic__=np.array("terrawatt-map"))
    with pytest.raises(FileFormatError, match="no valid format version"):
        TerrainMap.load(path)
    np.savez(path, __magic__=np.array("terrawatt-map"), __version__=np.array(MAP_FORMAT_VERSION))
    with pytest.raises(FileFormatError, match="lacks entry"):
        TerrainMap.load(path)



@pytest.mark.parametrize(("entry", "retype", "match"), [
    ("__cell_size_m__", lambda a: a > 0, r"'__cell_size_m__' holds booleans \(bool\); expected a real number"),
    ("__cell_size_m__", lambda a: a.astype(str), r"'__cell_size_m__' holds text .*expected a real number"),
    ("layer:elevation", lambda a: a > 0, r"'layer:elevation' holds booleans \(bool\); expected real numbers"),
    ("layer:elevation", lambda a: a.astype(str), "'layer:elevation' holds text"),
    ("layer:ground", lambda a: a.astype(np.float64), "'layer:ground' holds real numbers .*expected integer class ids"),
    ("layer:obstacle", lambda a: a.astype(np.int8), "'layer:obstacle' holds integers .*expected booleans"),
])
def test_load_refuses_an_entry_retyped_under_a_valid_crc(tmp_path, ramp_map, entry, retype, match):
    # found by tests/test_readers_properties.py: a boolean cell size read as 1.0, a text elevation parsed as numbers
    with np.load(ramp_map.save(tmp_path / "m.npz")) as data:
        content = dict(data)
    content[entry] = retype(content[entry])
    np.savez_compressed(tmp_path / "retyped.npz", **content)
    with pytest.raises(FileFormatError, match=match):
        TerrainMap.load(tmp_path / "retyped.npz")



# ------------------------------------------------------------------ hostile input
@pytest.mark.parametrize(
    ("args", "match"),
    [
        (("abc", 1.0), "elevation_m must be a 2-D array of real numbers, got str"),
        (([[0.0, "x"], [0.0, 0.0]], 1.0), "elevation_m must be a 2-D array of real numbers"),
        ((np.zeros((3, 3)), "1.0"), r"cell_size_m must be a real number, got '1.0' \(str\)"),
        ((np.zeros((3, 3)), "abc"), r"cell_size_m must be a real number, got 'abc' \(str\)"),
        ((np.zeros((3, 3)), 1.0, ("0", 0.0)), r"origin_xy_m\[0\] must be a real number"),
        ((np.zeros((3, 3)), 1e308), "no finite far corner"),
    ],
)
def test_strings_and_absurd_sizes_name_the_parameter(args, match):
    with pytest.raises(InvalidParameterError, match=match):
        TerrainMap(*args)


def test_save_onto_a_directory_is_a_parameter_error(tmp_path, flat_map):
    target = tmp_path / "m.npz"
    target.mkdir()
    with pytest.raises(InvalidParameterError, match="is a directory; expected a file name"):
        flat_map.save(target)
    assert target.is_dir() and os.listdir(tmp_path) == ["m.npz"]


def test_save_and_load_remove_temporaries_of_dead_saves_only(tmp_path, flat_map, dead_pid, live_pid):
    path = flat_map.save(tmp_path / "m.npz")
    dead = tmp_path / f".m.npz.{dead_pid}.k1ll3d_0.tmp"
    live = tmp_path / f".m.npz.{live_pid}.running.tmp"
    other = tmp_path / f".n.npz.{dead_pid}.k1ll3d_0.tmp"  # another target's: not ours to remove
    for leftover in (dead, live, other):
        leftover.write_bytes(b"half a map")
    flat_map.save(path)
    assert not dead.exists() and live.exists() and other.exists()
    dead.write_bytes(b"half a map")
    assert TerrainMap.load(path).same_grid(flat_map)
    assert not dead.exists() and live.exists() and other.exists()
