"""Ground classes from a land-cover raster (terrain.landcover)."""

from __future__ import annotations

import numpy as np
import pytest
from geo_fixtures import CLASSES, LAKE_UV, ROAD_U, lonlat, write_geo_scene

from terrain import (
    UNKNOWN_GROUND,
    DataError,
    FileFormatError,
    ImplausibleDataWarning,
    InvalidParameterError,
    LandcoverClasses,
    TerrainMap,
    ground_classes_from_landcover,
    read_geotiff,
    read_landcover_classes,
)

GRASS, ROAD, WATER, CROPS, NODATA = 30, 50, 80, 40, 0
MAPPING = {GRASS: "grass", ROAD: "asphalt", WATER: "obstacle"}


@pytest.fixture
def rasterio():
    return pytest.importorskip("rasterio")


def _write_codes(rasterio, path, codes, transform, crs="EPSG:32633", nodata=NODATA, dtype="uint8", count=1):
    with rasterio.open(path, "w", driver="GTiff", height=codes.shape[0], width=codes.shape[1], count=count,
                       dtype=dtype, crs=crs, transform=transform, nodata=nodata) as dst:
        for band in range(1, count + 1):
            dst.write(codes.astype(dtype), band)
    return path


# ------------------------------------------------------------------ the mapping file
def test_a_classes_file_is_read_with_labels_comments_and_blank_lines(tmp_path):
    path = tmp_path / "classes.csv"
    path.write_text("\ufeff# ESA WorldCover 2021\nCode, Ground ,label\n10,Obstacle,Tree cover\n\n30,grass,Grassland\n"
                    "95,unknown,Mangroves\n", encoding="utf-8")
    classes = read_landcover_classes(path)
    assert dict(classes.grounds_by_code) == {10: "obstacle", 30: "grass", 95: "unknown"}
    assert classes.ground_names == ("grass",) and classes.obstacle_codes == (10,)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("", r"is empty; expected a header 'code,ground'"),
        ("code,ground\n", "has a header but no rows"),
        ("code,name\n10,grass\n", r"line 1: header \['code', 'name'\]; .*\['ground'\] missing; \['name'\] unknown"),
        ("code,ground,ground\n10,grass,grass\n", r"line 1: header .*each once"),
        ("code,ground\n10,grass\n1O,sand\n", r"line 3: code '1O' is not a land-cover code; expected an integer"),
        ("code,ground\n-5,grass\n", r"line 2: code '-5' is not a land-cover code"),
        ("code,ground\n10.0,grass\n", r"line 2: code '10.0' is not a land-cover code"),
        ("code,ground\n99999999999,grass\n", r"line 2: code '99999999999' is not a land-cover code"),
        # past int()'s 4300-digit limit (a ValueError of Python's own), shown cut
        ("code,ground\n" + "9" * 5000 + ",grass\n", r"line 2: code '9{20}'\.\.\. is not a land-cover code"),
        ("code,ground\n" + "0" * 5000 + "7,grass\n", None),  # leading zeros: code 7, fine
        ("code,ground\n10,tall grass\n", r"line 2: ground 'tall grass' is not a ground name"),
        ("code,ground\n10,\n", r"line 2: ground '' is not a ground name"),
        ("code,ground\n10,grass,extra\n", r"line 2: 3 fields \['10', 'grass', 'extra'\]; the header has 2"),
        ("code,ground\n10,grass\n# water\n10,obstacle\n", r"line 4: code 10 is given twice \(first on line 2\)"),
        ('code,ground\n10,"grass\n', r"line 2: not a CSV row"),
    ],
)
def test_bad_classes_files_name_the_file_and_the_line(tmp_path, text, match):
    path = tmp_path / "classes.csv"
    path.write_text(text, encoding="utf-8")
    if match is None:
        assert read_landcover_classes(path).grounds_by_code == {7: "grass"}
        return
    with pytest.raises(FileFormatError, match=r"land-cover classes file '.*classes\.csv'.*" + match):
        read_landcover_classes(path)


def test_unreadable_classes_files_are_file_format_errors(tmp_path, monkeypatch):
    with pytest.raises(FileFormatError, match="does not exist"):
        read_landcover_classes(tmp_path / "none.csv")
    with pytest.raises(FileFormatError, match="is not a regular file"):
        read_landcover_classes(tmp_path)
    latin = tmp_path / "latin.csv"
    latin.write_bytes("code,ground,label\n10,grass,Prairie fleurie \xe9t\xe9\n".encode("latin-1"))
    with pytest.raises(FileFormatError, match="is not a UTF-8 text file"):
        read_landcover_classes(latin)
    big = tmp_path / "big.csv"
    big.write_text("code,ground\n" + "# padding\n" * 120_000)
    with pytest.raises(FileFormatError, match=r"holds \d+ bytes; a mapping of land-cover codes is at most 1024 KiB"):
        read_landcover_classes(big)


@pytest.mark.parametrize(
    ("mapping", "match"),
    [({}, "non-empty mapping"), ({-1: "grass"}, r"integers in \[0, 2147483647\], got -1"),
     ({1.5: "grass"}, "got 1.5"), ({10: "sand dunes"}, "code 10 needs a ground name"), ({10: 3}, "got 3")],
)
def test_bad_mappings_are_refused(mapping, match):
    with pytest.raises(InvalidParameterError, match=match):
        LandcoverClasses(mapping)


# ------------------------------------------------------------------ warping onto the map
@pytest.fixture
def utm_map() -> TerrainMap:
    """3 x 4 cells of 30 m in UTM zone 33 N, its south-west corner at (500 010, 4 982 900)."""
    return TerrainMap(np.zeros((3, 4)), 30.0, (500_010.0, 4_982_900.0), crs="EPSG:32633")


def _aligned(rasterio):
    """10 m land-cover cells whose north-west corner is the map's."""
    return rasterio.Affine(10.0, 0, 500_010.0, 0, -10.0, 4_982_990.0)


def _sub_cells(*blocks: list[int]) -> np.ndarray:
    """A 3 x 3 block of 10 m codes per map cell from 9 codes each (row-major, north first)."""
    return np.array(blocks).reshape(3, 3)


def test_each_map_cell_takes_the_majority_ground_of_its_land_cover_cells(rasterio, tmp_path, utm_map):
    g, r, w, c, n = GRASS, ROAD, WATER, CROPS, NODATA
    # the land cover covers the map's three columns west of its eastern one, 10 m cells aligned on the map's
    # (north-up: the first block row is the map's northern row)
    blocks = [
        [[g] * 5 + [r] * 4, [r] * 5 + [g] * 4, [w] * 5 + [g] * 4],
        [[n] * 6 + [g] * 2 + [r], [c] * 5 + [g] * 4, [w, r, g, w, r, g, w, r, g]],
        [[g, g, r, r, r, c, c, c, c], [n] * 9, [r] * 9],
    ]
    codes = np.block([[_sub_cells(*b) for b in row] for row in blocks])
    path = _write_codes(rasterio, tmp_path / "lc.tif", codes, _aligned(rasterio))
    with pytest.warns(ImplausibleDataWarning, match=r"leaves 50 % of the map's cells with unknown ground \(off the "
                                                    r"raster: 25 %.*code 40: 8 %"):
        out = ground_classes_from_landcover(utm_map, path, MAPPING)
    assert out.ground_names == {0: "asphalt", 1: "grass"}
    a, gr, u = 0, 1, UNKNOWN_GROUND
    expected_north_first = [
        [gr, a, u, u],  # 5 grass : 4 road; 5 road : 4 grass; water (an obstacle, ground kept); off the land cover
        [gr, u, u, u],  # nodata does not vote; 5 unmapped crops : 4 grass; a three-way tie of water, road, grass
        [u, u, a, u],   # 4 crops (unknown) beat 3 road and 2 grass; all nodata; all road
    ]
    ground, obstacle = out.ground[::-1].tolist(), out.obstacle[::-1].tolist()
    assert ground[1][2] in (a, gr, u)  # the tie: GDAL's choice (an obstacle if water wins)
    ground[1][2], obstacle[1][2] = u, False
    assert ground == expected_north_first
    assert obstacle == [[False, False, True, False], [False] * 4, [False] * 4]
    assert not utm_map.obstacle.any() and (utm_map.ground == u).all()  # the input map is not modified


def test_a_map_with_grounds_keeps_them_where_the_land_cover_says_nothing(rasterio, tmp_path, utm_map):
    tmap = utm_map.copy()
    tmap.ground_names = {0: "sand", 1: "asphalt"}
    tmap["ground"] = np.zeros(tmap.shape, np.int16)
    codes = np.full((9, 6), GRASS, np.uint8)
    codes[:, :3] = ROAD  # the western map column is road, the next grass; the rest lies off the land cover
    path = _write_codes(rasterio, tmp_path / "lc.tif", codes, _aligned(rasterio))
    out = ground_classes_from_landcover(tmap, path, MAPPING)  # half off the land cover, but sand: no warning
    assert out.ground_names == {0: "sand", 1: "asphalt", 2: "grass"}
    assert out.ground.tolist() == [[1, 2, 0, 0]] * 3


def test_a_land_cover_in_another_crs_lands_on_the_right_places(rasterio, tmp_path):
    """The synthetic scene: a DEM in EPSG:4326 read in UTM 32 N, a land cover in UTM 32 N at 10 m."""
    scene = write_geo_scene(tmp_path)
    tmap = ground_classes_from_landcover(read_geotiff(scene.dem, reproject_to="utm", cell_size_m=30.0),
                                         scene.landcover, scene.classes)
    assert set(tmap.ground_names.values()) == {"asphalt", "grass", "gravel"}

    def at(u, v, layer="ground"):
        x, y = tmap.lonlat_to_xy(*lonlat(u, v))
        value = tmap.sample(layer, x, y)
        return tmap.ground_names.get(int(value), "unknown") if layer == "ground" else bool(value)

    assert at(*LAKE_UV, "obstacle")
    assert at(0.95, 0.85, "obstacle")  # the forest
    assert at(ROAD_U, 0.5) == "asphalt" and at(0.5, 0.2) == "grass" and at(0.12, 0.5) == "gravel"
    assert at(0.1, 0.85) == "unknown"  # cropland: left out of the mapping
    assert at(0.95, 0.02) == "unknown" and not at(0.95, 0.02, "obstacle")  # nodata
    assert set(CLASSES.values()) - {"obstacle"} == set(tmap.ground_names.values())


def test_only_the_window_around_the_map_is_read(rasterio, tmp_path, utm_map, monkeypatch):
    """A 3000 x 3000 land cover (about 100 MB to read whole) serves a 3 x 4 cell map within a 1 MB budget."""
    codes = np.full((3000, 3000), GRASS, np.uint8)
    west, north = 500_010.0 - 15_000.0, 4_982_990.0 + 15_000.0
    path = _write_codes(rasterio, tmp_path / "big.tif", codes, rasterio.Affine(10.0, 0, west, 0, -10.0, north))
    monkeypatch.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", str(1024**2))
    out = ground_classes_from_landcover(utm_map, path, MAPPING)
    assert (out.ground == out.ground_id("grass")).all()
    monkeypatch.setenv("TERRAWATT_MEMORY_BUDGET_BYTES", "2000")
    with pytest.raises(FileFormatError, match=r"the \d+ x \d+ cells around the map would take .* than the memory budget"):
        ground_classes_from_landcover(utm_map, path, MAPPING)


def test_bad_land_covers_are_refused(rasterio, tmp_path, utm_map):
    transform = _aligned(rasterio)
    codes = np.full((9, 12), GRASS)
    with pytest.raises(InvalidParameterError, match="the map has no CRS, so a land-cover raster cannot be placed"):
        ground_classes_from_landcover(TerrainMap(np.zeros((3, 3)), 1.0),
                                      _write_codes(rasterio, tmp_path / "a.tif", codes, transform), MAPPING)
    with pytest.raises(FileFormatError, match="has no CRS; a land cover is placed on the map by its CRS"):
        ground_classes_from_landcover(utm_map, _write_codes(rasterio, tmp_path / "b.tif", codes, transform, crs=None),
                                      MAPPING)
    with pytest.raises(FileFormatError, match="band 1 holds float32 values; a land cover holds integer class codes"):
        ground_classes_from_landcover(utm_map, _write_codes(rasterio, tmp_path / "c.tif", codes, transform,
                                                            dtype="float32", nodata=None), MAPPING)
    two = _write_codes(rasterio, tmp_path / "d.tif", codes, transform, count=2)
    with pytest.raises(FileFormatError, match="has 2 bands; name the band of class codes with band=N"):
        ground_classes_from_landcover(utm_map, two, MAPPING)
    assert ground_classes_from_landcover(utm_map, two, MAPPING, band=2).ground_names == {0: "grass"}
    with pytest.raises(InvalidParameterError, match=r"band must be an integer in 1\.\.2, got 3"):
        ground_classes_from_landcover(utm_map, two, MAPPING, band=3)
    far = _write_codes(rasterio, tmp_path / "e.tif", codes, rasterio.Affine(10.0, 0, 600_000.0, 0, -10.0, 4_000_000.0))
    with pytest.raises(InvalidParameterError, match=r"does not overlap the map: it spans lon 16\.1.*; the map lon 15"):
        ground_classes_from_landcover(utm_map, far, MAPPING)
    with pytest.raises(FileFormatError, match="does not exist"):
        ground_classes_from_landcover(utm_map, tmp_path / "none.tif", MAPPING)
    text = tmp_path / "not.tif"
    text.write_text("not a raster")
    with pytest.raises(FileFormatError, match="cannot read .* as a raster"):
        ground_classes_from_landcover(utm_map, text, MAPPING)


# ------------------------------------------------------------------ a land cover with nothing to say
def test_a_land_cover_all_nodata_over_the_map_is_refused(rasterio, tmp_path, utm_map):
    """Nodata around the map (valid codes far away) would leave every cell unknown without a word."""
    codes = np.full((60, 60), NODATA, np.uint8)
    codes[-5:, -5:] = GRASS  # valid codes, but not near the map
    path = _write_codes(rasterio, tmp_path / "lc.tif", codes, _aligned(rasterio))
    with pytest.raises(DataError, match=r"land-cover GeoTIFF '.*lc\.tif' holds only nodata \(value 0\) in the 11 x 14 "
                                        r"raster cells over the map: there is no land cover .*is it the land cover of"):
        ground_classes_from_landcover(utm_map, path, MAPPING)


def test_a_classes_file_none_of_whose_codes_the_raster_holds_is_refused(rasterio, tmp_path, utm_map):
    codes = np.full((9, 12), GRASS, np.uint8)
    codes[:, :6] = CROPS
    path = _write_codes(rasterio, tmp_path / "lc.tif", codes, _aligned(rasterio))
    other = tmp_path / "other_product.csv"
    other.write_text("code,ground\n1,grass\n2,asphalt\n3,obstacle\n", encoding="utf-8")
    with pytest.raises(DataError, match=r"'.*lc\.tif' holds codes \[30, 40\] in the \d+ x \d+ raster cells over the "
                                        r"map, none of them in land-cover classes file '.*other_product\.csv' \(codes "
                                        r"\[1, 2, 3\]\): no cell would take a ground"):
        ground_classes_from_landcover(utm_map, path, other)
    many = {code: "grass" for code in range(100, 120)}
    with pytest.raises(DataError, match=r"none of them in the mapping \(codes \[100, 101, .*, 107, "
                                        r"\.\.\. \(12 more\)\]\)"):
        ground_classes_from_landcover(utm_map, path, many)


def test_a_land_cover_leaving_much_of_the_map_unknown_warns_which_codes_and_what_share(rasterio, tmp_path, utm_map):
    codes = np.full((9, 12), GRASS, np.uint8)
    codes[:, :6] = CROPS  # the western half of the map: a code the mapping omits
    codes[:3, 6:9] = NODATA  # one northern cell
    path = _write_codes(rasterio, tmp_path / "lc.tif", codes, _aligned(rasterio))
    with pytest.warns(ImplausibleDataWarning) as caught:
        out = ground_classes_from_landcover(utm_map, path, MAPPING)
    (warning,) = [w for w in caught if issubclass(w.category, ImplausibleDataWarning)]
    assert str(warning.message) == (
        f"land-cover GeoTIFF {str(path)!r} leaves 58 % of the map's cells with unknown ground (code 40: 50 %, "
        "nodata: 8 %), priced as the planner's unknown_ground; codes [50, 80] of the mapping are "
        "nowhere over the map; map the omitted codes in the classes file, or give a land cover that covers the map")
    assert warning.message.parameter == "unknown_ground"  # a front end says it its own way
    assert (out.ground[:, 2:] == out.ground_id("grass")).sum() == 5 and (out.ground[:, :2] == UNKNOWN_GROUND).all()


def test_stated_unknown_codes_absent_classes_and_small_gaps_do_not_warn(rasterio, tmp_path, utm_map, recwarn):
    codes = np.full((9, 12), GRASS, np.uint8)
    codes[:, :6] = CROPS
    codes[:3, 9:] = NODATA  # a twelfth of the map
    path = _write_codes(rasterio, tmp_path / "lc.tif", codes, _aligned(rasterio))
    # crops stated unknown; road and water absent from this small map (a whole-product mapping)
    out = ground_classes_from_landcover(utm_map, path, {**MAPPING, CROPS: "unknown"})
    assert not [w for w in recwarn if issubclass(w.category, ImplausibleDataWarning)]
    assert (out.ground[:, :2] == UNKNOWN_GROUND).all()
