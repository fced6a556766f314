"""Tests of terrain.procedural: exact builders, seeded procedural maps, the bundled example map."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from terrain import (
    EXAMPLE_GOAL_XY_M,
    EXAMPLE_START_XY_M,
    UNKNOWN_GROUND,
    InvalidParameterError,
    TerrainMap,
    UnknownNameError,
    example_map,
    flat_map,
    procedural_map,
    ramp_map,
    wall_map,
)

REPO = Path(__file__).resolve().parents[2]


# -------------------------------------------------------------- exact builders
def test_flat_map():
    tmap = flat_map((3, 5), 0.5, elevation_m=12.0, ground="sand", origin_xy_m=(1.0, 2.0))
    assert tmap.bounds == (1.0, 2.0, 3.5, 3.5)
    assert np.all(tmap.elevation_m == 12.0) and np.all(tmap.slope_rad == 0.0)
    assert tmap.ground_names == {0: "sand"} and np.all(tmap.ground == 0)
    assert not tmap.obstacle.any()


def test_flat_map_without_ground_is_unknown():
    tmap = flat_map((3, 5), ground=None)
    assert tmap.ground_names == {} and np.all(tmap.ground == UNKNOWN_GROUND)


@pytest.mark.parametrize("shape", [(5,), (1, 5), (2.0, 3), (True, 4), "ab"])
def test_builders_reject_bad_shapes(shape):
    for build in (flat_map, ramp_map, wall_map, procedural_map):
        with pytest.raises(InvalidParameterError, match="shape must be"):
            build(shape)


def test_flat_map_rejects_bad_values():
    with pytest.raises(InvalidParameterError, match="elevation_m must be finite"):
        flat_map((3, 3), elevation_m=np.nan)
    with pytest.raises(InvalidParameterError, match="ground must be a non-empty string"):
        flat_map((3, 3), ground="")
    with pytest.raises(InvalidParameterError, match="cell_size_m"):
        flat_map((3, 3), 0.0)


@pytest.mark.parametrize("grade", [0.15, -0.08])
def test_ramp_map_along_x(grade):
    tmap = ramp_map((4, 6), 0.4, grade, "x", origin_xy_m=(50.0, 7.0))
    x, _ = tmap.cell_centres()
    np.testing.assert_allclose(tmap.elevation_m, np.broadcast_to(grade * (x - 50.0), (4, 6)), rtol=1e-12)
    np.testing.assert_allclose(tmap["grad_x"], grade, rtol=1e-12)
    np.testing.assert_allclose(tmap["grad_y"], 0.0, atol=1e-15)
    np.testing.assert_allclose(tmap.slope_rad, np.arctan(abs(grade)), rtol=1e-12)


def test_ramp_map_along_y():
    tmap = ramp_map((5, 3), 2.0, 0.05, "y")
    np.testing.assert_allclose(tmap.elevation_m[:, 0], 0.05 * (np.arange(5) + 0.5) * 2.0)
    np.testing.assert_allclose(tmap["grad_y"], 0.05, rtol=1e-12)
    np.testing.assert_allclose(tmap["grad_x"], 0.0, atol=1e-15)


def test_ramp_map_errors():
    with pytest.raises(UnknownNameError, match="axis must be 'x' or 'y'"):
        ramp_map((3, 3), 1.0, 0.1, "z")
    with pytest.raises(InvalidParameterError, match="grade must be finite"):
        ramp_map((3, 3), 1.0, np.inf)


def test_wall_map_default_gap():
    tmap = wall_map((40, 30))
    blocked_rows = np.flatnonzero(tmap.obstacle[:, 15])
    assert sorted(set(range(40)) - set(blocked_rows.tolist())) == [30, 31, 32, 33]
    assert tmap.obstacle.sum() == 36 and np.all(tmap.elevation_m == 0.0)


def test_wall_fixture_matches_its_docstring(wall_map):
    assert np.flatnonzero(~wall_map.obstacle[:, 20]).tolist() == [30, 31, 32, 33]
    assert wall_map.obstacle.sum() == 36
    assert wall_map.sample("obstacle", 20.5, 10.0) and not wall_map.sample("obstacle", 20.5, 31.0)


def test_closed_wall():
    assert wall_map((6, 6), wall_col=0, gap_rows=(0, 0)).obstacle[:, 0].all()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"wall_col": 6}, "wall_col must be <= 5"),
        ({"wall_col": -1}, "wall_col must be >= 0"),
        ({"wall_col": 2.0}, "wall_col must be an integer"),
        ({"gap_rows": (4, 2)}, "gap_rows must be integers"),
        ({"gap_rows": (0, 7)}, "gap_rows must be integers"),
        ({"gap_rows": (1.0, 2)}, "gap_rows must be integers"),
        ({"gap_rows": 3}, "gap_rows must be integers"),
    ],
)
def test_wall_map_errors(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        wall_map((6, 6), **kwargs)


# ------------------------------------------------------------- procedural map
def test_procedural_map_is_deterministic_per_seed():
    a = procedural_map((48, 64), 0.5, seed=11)
    b = procedural_map((48, 64), 0.5, seed=11)
    c = procedural_map((48, 64), 0.5, seed=12)
    for name in ("elevation", "ground", "obstacle"):
        np.testing.assert_array_equal(a[name], b[name])
    assert not np.array_equal(a.elevation_m, c.elevation_m)
    assert not np.array_equal(a.ground, c.ground)


def test_procedural_components_draw_independent_streams():
    a = procedural_map((64, 64), seed=5, obstacle_fraction=0.0)
    b = procedural_map((64, 64), seed=5, obstacle_fraction=0.05, n_walls=2)
    np.testing.assert_array_equal(a.elevation_m, b.elevation_m)
    np.testing.assert_array_equal(a.ground, b.ground)
    assert not a.obstacle.any() and b.obstacle.any()


def test_procedural_grid_and_names():
    tmap = procedural_map((30, 50), 2.0, seed=0, origin_xy_m=(-10.0, 5.0), grounds=("grass", "gravel"))
    assert tmap.shape == (30, 50) and tmap.bounds == (-10.0, 5.0, 90.0, 65.0)
    assert tmap.ground_names == {0: "grass", 1: "gravel"}
    assert set(np.unique(tmap.ground).tolist()) == {0, 1}


def test_hill_slopes_hit_the_requested_95th_percentile():
    tmap = procedural_map((96, 96), 0.5, seed=2, slope_deg=7.0, n_ridges=0)
    p95 = np.degrees(np.percentile(tmap.slope_rad, 95))
    assert p95 == pytest.approx(7.0, abs=0.05)


def test_default_slopes_are_robot_friendly_with_a_few_steep_parts():
    tmap = procedural_map((128, 128), 1.0, seed=4)
    slope_deg = np.degrees(tmap.slope_rad)
    assert np.percentile(slope_deg, 90) < 15.0
    assert slope_deg.max() > 15.0  # the ridge flanks


def test_ridge_height_and_flank_slope():
    tmap = procedural_map(
        (128, 128), 0.25, seed=1, n_hills=0, slope_deg=0.0, ridge_height_m=0.5, ridge_slope_deg=20.0
    )
    assert tmap.elevation_m.max() == pytest.approx(0.5, rel=0.02)
    assert np.degrees(tmap.slope_rad.max()) == pytest.approx(20.0, rel=0.03)


def test_flat_when_no_relief_is_asked():
    tmap = procedural_map((32, 32), seed=0, n_hills=0, slope_deg=0.0, n_ridges=0)
    assert np.all(tmap.elevation_m == 0.0)


def test_ground_patches_are_contiguous_blobs():
    tmap = procedural_map((128, 128), seed=3)
    assert sorted(tmap.ground_names.values()) == ["asphalt", "grass", "sand", "snow"]
    for gid in tmap.ground_names:
        labels, n_parts = ndimage.label(tmap.ground == gid)
        sizes = np.bincount(labels.ravel())[1:]
        assert 1 <= n_parts <= 15, (gid, n_parts)
        assert sizes.max() >= 0.25 * sizes.sum()


def test_no_grounds_leaves_unknown():
    tmap = procedural_map((32, 32), seed=0, grounds=())
    assert tmap.ground_names == {} and np.all(tmap.ground == UNKNOWN_GROUND)


@pytest.mark.parametrize("fraction", [0.0, 0.02, 0.1])
def test_rocks_cover_the_requested_fraction(fraction):
    tmap = procedural_map((100, 100), seed=6, obstacle_fraction=fraction)
    covered = tmap.obstacle.mean()
    assert fraction <= covered <= fraction + 0.01


def test_walls_add_obstacles():
    without = procedural_map((100, 100), seed=8, obstacle_fraction=0.0)
    with_walls = procedural_map((100, 100), seed=8, obstacle_fraction=0.0, n_walls=2)
    assert not without.obstacle.any() and with_walls.obstacle.sum() >= 30


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"seed": -1}, r"seed must be None or an integer in \[0, 2\*\*32\)"),
        ({"seed": 1.5}, r"seed must be None or an integer in \[0, 2\*\*32\)"),
        ({"seed": True}, r"seed must be None or an integer in \[0, 2\*\*32\)"),
        ({"seed": 2**32}, r"seed must be None or an integer in \[0, 2\*\*32\)"),
        ({"cell_size_m": 0.0}, "cell_size_m must be > 0"),
        ({"cell_size_m": "1"}, "cell_size_m must be a real number"),
        ({"n_hills": -1}, "n_hills must be >= 0"),
        ({"n_walls": 1.0}, "n_walls must be an integer"),
        ({"slope_deg": 75.0}, "slope_deg must be <= 60"),
        ({"slope_deg": np.nan}, "slope_deg must be finite"),
        ({"ridge_slope_deg": 0.0}, "ridge_slope_deg must be > 0"),
        ({"ridge_slope_deg": 85.0}, "ridge_slope_deg must be <= 80"),
        ({"obstacle_fraction": 0.6}, "obstacle_fraction must be <= 0.5"),
        ({"grounds": "sand"}, "grounds must be a sequence of names"),
        ({"grounds": ("sand", "sand")}, "grounds must be unique"),
        ({"hill_size_m": -3.0}, "hill_size_m must be > 0"),
        ({"rock_radius_m": 0.5}, "rock_radius_m must be at least the cell size"),
    ],
)
def test_procedural_map_errors(kwargs, match):
    with pytest.raises(InvalidParameterError, match=match):
        procedural_map((32, 32), **kwargs)


# ---------------------------------------------------------------- example map
def test_example_map_content():
    tmap = example_map()
    assert tmap.shape == (160, 160) and tmap.cell_size_m == 1.0 and tmap.origin_xy_m == (0.0, 0.0)
    assert sorted(tmap.ground_names.values()) == ["asphalt", "grass", "sand", "snow"]
    for xy in (EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M):
        assert tmap.contains(*xy) and not tmap.sample("obstacle", *xy)
    assert 0 < tmap.obstacle.sum() < 0.02 * tmap.obstacle.size
    # the straight route climbs the hill and crosses the sand
    heights, _ = tmap.sample_segment("elevation", EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M)
    start_z = tmap.sample("elevation", *EXAMPLE_START_XY_M)
    assert heights.max() - start_z > 4.0
    grounds, lengths = tmap.sample_segment("ground", EXAMPLE_START_XY_M, EXAMPLE_GOAL_XY_M)
    assert lengths[grounds == tmap.ground_id("sand")].sum() > 10.0


def test_example_map_is_reproducible_from_its_script(tmp_path):
    script_path = REPO / "examples" / "make_example_map.py"
    spec = importlib.util.spec_from_file_location("make_example_map", script_path)
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    assert script.main(["--out", str(tmp_path / "map.npz")]) == 0
    rebuilt, bundled = TerrainMap.load(tmp_path / "map.npz"), example_map()
    assert rebuilt.same_grid(bundled) and rebuilt.ground_names == bundled.ground_names
    assert rebuilt.keys() == bundled.keys()
    for name in bundled:
        np.testing.assert_array_equal(rebuilt[name], bundled[name])
    assert (REPO / "terrain" / "data" / "example_map.npz").stat().st_size < 300 * 1024


def test_a_seed_of_none_is_allowed_and_the_default_seed_is_kept():
    assert procedural_map((16, 16), seed=None).shape == (16, 16)
    np.testing.assert_array_equal(procedural_map((16, 16)).elevation_m, procedural_map((16, 16), seed=0).elevation_m)

