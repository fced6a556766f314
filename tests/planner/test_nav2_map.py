"""Nav2 maps: the obstacle layer as PGM + YAML (rows flipped, origin at the lower-left corner) and the raw energy costmap."""

from __future__ import annotations

import numpy as np
import pytest

import terrain
from planner import energy_costmap, write_nav2_map
from planner.cost_spec import CostSpec
from planner.nav2_map import (
    NAV2_FREE_PIXEL,
    NAV2_OCCUPIED_PIXEL,
    NAV2_UNKNOWN_PIXEL,
    read_nav2_map,
    read_pgm,
    write_nav2_costmap,
)
from terrawatt_base.errors import FileFormatError, GridMismatchError, InvalidParameterError


@pytest.fixture
def marked_map() -> terrain.TerrainMap:
    """5 rows x 7 cols of 0.5 m from (10, 20): one obstacle in the south-west corner cell (row 0, col 0)
    and one at row 3, col 5, so a missing flip or transposition shows."""
    obstacle = np.zeros((5, 7), bool)
    obstacle[0, 0] = obstacle[3, 5] = True
    return terrain.TerrainMap(np.zeros((5, 7)), 0.5, (10.0, 20.0), obstacle=obstacle)


def _yaml_lines(path) -> dict[str, str]:
    return dict(line.split(": ", 1) for line in path.read_text().splitlines() if line and not line.startswith("#"))


def test_round_trip_gives_the_obstacle_layer_back(tmp_path, marked_map):
    yaml_path = write_nav2_map(tmp_path / "site.yaml", marked_map)
    back = read_nav2_map(yaml_path)
    np.testing.assert_array_equal(back.occupied, marked_map.obstacle)
    np.testing.assert_array_equal(back.free, ~marked_map.obstacle)
    assert not back.unknown.any() and back.mode == "trinary" and back.image == tmp_path / "site.pgm"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["site.pgm", "site.yaml"]


def test_the_pgm_is_p5_with_north_as_its_first_row(tmp_path, marked_map):
    write_nav2_map(tmp_path / "site.yaml", marked_map)
    raw = (tmp_path / "site.pgm").read_bytes()
    assert raw.startswith(b"P5\n") and b"\n7 5\n255\n" in raw
    pixels = read_pgm(tmp_path / "site.pgm")
    assert pixels.shape == (5, 7) and pixels.dtype == np.uint8
    assert pixels[4, 0] == NAV2_OCCUPIED_PIXEL  # map row 0 (south) is the image's last row
    assert pixels[1, 5] == NAV2_OCCUPIED_PIXEL  # map row 3 is image row 5 - 1 - 3
    assert int((pixels == NAV2_OCCUPIED_PIXEL).sum()) == 2 and set(np.unique(pixels)) == {0, NAV2_FREE_PIXEL}


def test_the_yaml_has_nav2s_keys_and_the_lower_left_corner_as_origin(tmp_path, marked_map):
    write_nav2_map(tmp_path / "site.yaml", marked_map)
    assert _yaml_lines(tmp_path / "site.yaml") == {
        "image": "site.pgm", "mode": "trinary", "resolution": "0.5", "origin": "[10.0, 20.0, 0.0]",
        "negate": "0", "occupied_thresh": "0.65", "free_thresh": "0.196"}
    back = read_nav2_map(tmp_path / "site.yaml")
    assert back.grid == marked_map.grid and back.origin_yaw_rad == 0.0
    # the centre of the obstacle cell (3, 5) in the map frame is inside the cell Nav2 marks
    x, y = marked_map.xy(3, 5)
    assert back.grid.rowcol(x, y) == (3, 5) and back.occupied[3, 5]


def test_a_frame_origin_moves_the_yaml_origin(tmp_path, marked_map):
    write_nav2_map(tmp_path / "site.yaml", marked_map, frame_origin_xy_m=(4.0, 5.5))
    assert _yaml_lines(tmp_path / "site.yaml")["origin"] == "[6.0, 14.5, 0.0]"


@pytest.mark.parametrize("origin", [(1e308, 0.0), (0.0, -1e308), (10.0, 20.0 + 1.0e7 + 3.0), (-1e7, -1e7)])
def test_a_frame_origin_far_from_the_map_is_refused_before_writing(tmp_path, marked_map, origin):
    """1e308 would be written into the YAML (or overflow to -inf); an origin is a point near the site."""
    costmap = energy_costmap(CostSpec().build(marked_map))
    with pytest.raises(InvalidParameterError, match=r"^frame_origin_xy_m \(.*\) lies .* m from the map \(x 10 to "
                                                    r"13\.5, y 20 to 22\.5 m\); a map frame origin other than \(0, 0\) "
                                                    r"must lie within 1e\+07 m of the map's bounds"):
        write_nav2_map(tmp_path / "site.yaml", marked_map, frame_origin_xy_m=origin)
    with pytest.raises(InvalidParameterError, match="must lie within 1e"):
        write_nav2_costmap(tmp_path / "energy.yaml", costmap, frame_origin_xy_m=origin)
    assert list(tmp_path.iterdir()) == []
    far_but_plausible = (10.0, 20.0 + 1.0e7 - 3.0)  # e.g. a UTM zone's (500000, 0) seen from a southern site
    write_nav2_map(tmp_path / "site.yaml", marked_map, frame_origin_xy_m=far_but_plausible)
    write_nav2_map(tmp_path / "zero.yaml", terrain.flat_map((3, 3), 1.0, origin_xy_m=(3e7, 0.0)))  # (0, 0): as it is


def test_unknown_cells_are_205_and_nav2_reads_them_as_unknown(tmp_path, marked_map):
    unknown = np.zeros(marked_map.shape, bool)
    unknown[2, 1:3] = True
    back = read_nav2_map(write_nav2_map(tmp_path / "site.yaml", marked_map, unknown=unknown))
    assert (back.pixels[unknown] == NAV2_UNKNOWN_PIXEL).all()
    np.testing.assert_array_equal(back.unknown, unknown)
    np.testing.assert_array_equal(back.occupied, marked_map.obstacle)
    # Nav2's trinary rule: occupancy 1 - pixel/255 above occupied_thresh, below free_thresh, else unknown
    occ = 1.0 - np.array([NAV2_OCCUPIED_PIXEL, NAV2_FREE_PIXEL, NAV2_UNKNOWN_PIXEL]) / 255.0
    assert occ[0] > back.occupied_thresh and occ[1] < back.free_thresh
    assert back.free_thresh <= occ[2] <= back.occupied_thresh  # with free_thresh 0.25, 205 would load as free


def test_with_a_cost_the_too_steep_cells_are_occupied_too(tmp_path):
    tmap = terrain.procedural_map((30, 40), 1.0, seed=3)
    cost = CostSpec(max_slope_deg=8.0).build(tmap)
    assert (cost.blocked & ~tmap.obstacle).any()
    back = read_nav2_map(write_nav2_map(tmp_path / "site.yaml", tmap, cost=cost))
    np.testing.assert_array_equal(back.occupied, cost.blocked)
    with pytest.raises(GridMismatchError):
        write_nav2_map(tmp_path / "other.yaml", terrain.flat_map((8, 8), 1.0), cost=cost)


def test_the_energy_costmap_is_written_in_raw_mode_proportional_to_energy(tmp_path):
    ground = np.zeros((6, 8), np.int16)
    ground[:, 4:] = 1  # east half sand
    obstacle = np.zeros((6, 8), bool)
    obstacle[5, 0] = True
    tmap = terrain.TerrainMap(np.zeros((6, 8)), 1.0, ground=ground, ground_names={0: "asphalt", 1: "sand"},
                              obstacle=obstacle)
    costmap = energy_costmap(CostSpec().build(tmap))
    asphalt, sand = costmap.energy_per_metre_j[0, 0], costmap.energy_per_metre_j[0, 7]
    assert sand > asphalt
    back = read_nav2_map(write_nav2_costmap(tmp_path / "energy.yaml", costmap))
    assert back.mode == "raw" and back.grid == tmap.grid
    expected = np.where(ground == 1, 99, round(99 * asphalt / sand))
    expected[obstacle] = 100
    np.testing.assert_array_equal(back.occupancy, expected)
    text = (tmp_path / "energy.yaml").read_text()
    assert "trinary_costmap: false" in text and f"one cost unit = {float(sand) / 99!r} J/m" in text
    halved = read_nav2_map(write_nav2_costmap(tmp_path / "half.yaml", costmap, top_j_per_m=sand / 2))
    assert (halved.occupancy[ground == 1] == 99).all()  # clipped


def test_an_infinite_energy_is_read_as_unknown(tmp_path, flat_map):
    costmap = energy_costmap(CostSpec().build(flat_map))
    values = costmap.energy_per_metre_j.copy()
    values[1, 2] = np.inf
    edited = type(costmap)(values, costmap.grid, None, "max", costmap.speed_mps)
    back = read_nav2_map(write_nav2_costmap(tmp_path / "e.yaml", edited))
    assert back.occupancy[1, 2] == -1 and (np.delete(back.occupancy.ravel(), 1 * 30 + 2) == 99).all()


def test_bad_arguments_are_refused(tmp_path, marked_map):
    with pytest.raises(InvalidParameterError, match=r"'.yaml' or '.yml'"):
        write_nav2_map(tmp_path / "site.pgm", marked_map)
    with pytest.raises(InvalidParameterError, match="boolean"):
        write_nav2_map(tmp_path / "site.yaml", marked_map, unknown=np.zeros(marked_map.shape))
    with pytest.raises(GridMismatchError, match="unknown has shape"):
        write_nav2_map(tmp_path / "site.yaml", marked_map, unknown=np.zeros((2, 2), bool))
    with pytest.raises(InvalidParameterError, match="must be a TerrainMap"):
        write_nav2_map(tmp_path / "site.yaml", marked_map.obstacle)
    with pytest.raises(InvalidParameterError, match="top_j_per_m"):
        write_nav2_costmap(tmp_path / "e.yaml", energy_costmap(CostSpec().build(marked_map)), top_j_per_m=0)
    assert list(tmp_path.iterdir()) == []


def test_reading_bad_files_fails_clearly(tmp_path, marked_map):
    write_nav2_map(tmp_path / "site.yaml", marked_map)
    (tmp_path / "nokeys.yaml").write_text("image: site.pgm\nresolution: 0.5\n")
    with pytest.raises(FileFormatError, match="lacks"):
        read_nav2_map(tmp_path / "nokeys.yaml")
    (tmp_path / "nested.yaml").write_text("map:\n  - image: site.pgm\n")
    with pytest.raises(FileFormatError, match="not a flat"):
        read_nav2_map(tmp_path / "nested.yaml")
    (tmp_path / "ascii.pgm").write_bytes(b"P2\n2 1\n255\n0 254\n")
    with pytest.raises(FileFormatError, match="not a binary PGM"):
        read_pgm(tmp_path / "ascii.pgm")
    (tmp_path / "short.pgm").write_bytes((tmp_path / "site.pgm").read_bytes()[:-3])
    with pytest.raises(FileFormatError, match="truncated"):
        read_pgm(tmp_path / "short.pgm")
    (tmp_path / "wide.pgm").write_bytes(b"P5\n1 1\n65535\n\x00\x00")
    with pytest.raises(FileFormatError, match="8-bit"):
        read_pgm(tmp_path / "wide.pgm")


def test_a_hand_written_nav2_yaml_with_comments_and_quotes_is_read(tmp_path, marked_map):
    write_nav2_map(tmp_path / "site.yaml", marked_map)
    (tmp_path / "hand.yaml").write_text(
        "# saved by map_saver\nimage: 'site.pgm'  # the image\nmode: trinary\nresolution: 0.500\n"
        "origin: [10, 20, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    np.testing.assert_array_equal(read_nav2_map(tmp_path / "hand.yaml").occupied, marked_map.obstacle)
