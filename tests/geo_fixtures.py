"""A synthetic georeferenced scene for the geographic tests, written on demand (no binary fixtures).

- ``dem.tif``: 240 x 240 cells of 1 arc-second in EPSG:4326 (lon 10.0 to 10.0667 E, lat
  46.0 to 46.0667 N, about 5.2 x 7.4 km), rolling hills 430 to 650 m with a hill in the
  middle, slopes under 10 degrees;
- ``landcover.tif``: ESA WorldCover-style uint8 codes in UTM zone 32 N (EPSG:32632), 10 m
  cells, a margin around the DEM: grassland (30) everywhere but a lake (80) in the
  south-west, a forest (10) in the north-east, a 60 m wide north-south road (50) east of the
  hill, a bare patch (60) in the west, cropland (40, left out of the mapping) in the
  north-west and a nodata block (0) in the south-east corner;
- ``classes.csv``: ``10 obstacle, 30 grass, 50 asphalt, 60 gravel, 80 obstacle`` (40 omitted).

Places are given as fractions ``(u, v)`` of the DEM's extent (u east, v north) and
converted with :func:`lonlat`; :data:`START_UV` and :data:`GOAL_UV` lie west of the road, on
grass, at either end of it: the least-energy route drives on the road.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: The DEM's north-west corner (lon, lat) and its extent (degrees).
WEST, NORTH, SIZE_DEG, CELLS = 10.0, 46.0 + 240 / 3600, 240 / 3600, 240
#: Land-cover codes (ESA WorldCover 2021).
TREES, CROPLAND, GRASS, BUILT_UP, BARE, WATER, NODATA = 10, 40, 30, 50, 60, 80, 0
#: The mapping written to classes.csv.
CLASSES = {TREES: "obstacle", GRASS: "grass", BUILT_UP: "asphalt", BARE: "gravel", WATER: "obstacle"}
#: The road's centre line (u) and half width (m); its ends (v).
ROAD_U, ROAD_HALF_WIDTH_M, ROAD_V = 0.75, 30.0, (0.06, 0.94)
#: Lake: centre (u, v) and radius (m).
LAKE_UV, LAKE_RADIUS_M = (0.3, 0.3), 600.0
#: Start and goal as fractions of the extent.
START_UV, GOAL_UV = (0.68, 0.1), (0.68, 0.9)
_M_PER_DEG_LAT = 111_200.0


def lonlat(u: float, v: float) -> tuple[float, float]:
    """(lon, lat) of the fractions ``(u, v)`` of the DEM's extent (u east, v north)."""
    return WEST + u * SIZE_DEG, NORTH - SIZE_DEG + v * SIZE_DEG


def _uv(lon: np.ndarray, lat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return (lon - WEST) / SIZE_DEG, (lat - (NORTH - SIZE_DEG)) / SIZE_DEG


def elevation_m(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The DEM's terrain (m) at fractions of its extent."""
    hill = 160.0 * np.exp(-((u - 0.45) ** 2 + (v - 0.55) ** 2) / (2 * 0.13**2))
    knoll = 60.0 * np.exp(-((u - 0.85) ** 2 + (v - 0.25) ** 2) / (2 * 0.08**2))
    rolling = 12.0 * np.sin(7.0 * u + 1.0) * np.cos(5.0 * v)
    return 470.0 + hill + knoll + rolling + 20.0 * v


@dataclass(frozen=True)
class GeoScene:
    """The files of :func:`write_geo_scene` and the scene's key places (lon, lat)."""

    dem: Path
    landcover: Path
    classes: Path
    start_lonlat: tuple[float, float]
    goal_lonlat: tuple[float, float]
    lake_lonlat: tuple[float, float]


def write_geo_scene(folder: Path) -> GeoScene:
    """Write dem.tif, landcover.tif and classes.csv into ``folder`` (needs rasterio)."""
    import rasterio
    from rasterio.warp import transform, transform_bounds

    folder.mkdir(parents=True, exist_ok=True)
    step = SIZE_DEG / CELLS
    centres = (np.arange(CELLS) + 0.5) / CELLS
    u, v = np.meshgrid(centres, centres[::-1])  # north-up: row 0 is the north edge
    dem = folder / "dem.tif"
    with rasterio.open(dem, "w", driver="GTiff", height=CELLS, width=CELLS, count=1, dtype="float32",
                       crs="EPSG:4326", transform=rasterio.Affine(step, 0.0, WEST, 0.0, -step, NORTH),
                       compress="deflate") as dst:
        dst.write(elevation_m(u, v).astype(np.float32), 1)
        dst.units = ("m",)

    utm, d, margin = "EPSG:32632", 10.0, 300.0
    left, bottom, right, top = transform_bounds("EPSG:4326", utm, WEST, NORTH - SIZE_DEG, WEST + SIZE_DEG, NORTH)
    left, bottom, right, top = left - margin, bottom - margin, right + margin, top + margin
    cols, rows = int(np.ceil((right - left) / d)), int(np.ceil((top - bottom) / d))
    xs = left + (np.arange(cols) + 0.5) * d
    ys = top - (np.arange(rows) + 0.5) * d
    gx, gy = np.meshgrid(xs, ys)
    lon, lat = transform(utm, "EPSG:4326", gx.ravel().tolist(), gy.ravel().tolist())
    lu, lv = _uv(np.asarray(lon).reshape(gx.shape), np.asarray(lat).reshape(gx.shape))
    m_per_u = SIZE_DEG * _M_PER_DEG_LAT * np.cos(np.radians(NORTH - SIZE_DEG / 2))
    m_per_v = SIZE_DEG * _M_PER_DEG_LAT
    codes = np.full(gx.shape, GRASS, np.uint8)
    codes[(lu < 0.2) & (lv > 0.7)] = CROPLAND
    codes[(np.abs(lu - 0.12) < 0.06) & (np.abs(lv - 0.5) < 0.08)] = BARE
    codes[(lu > 0.85) & (lv > 0.7)] = TREES
    codes[np.hypot((lu - LAKE_UV[0]) * m_per_u, (lv - LAKE_UV[1]) * m_per_v) < LAKE_RADIUS_M] = WATER
    codes[(np.abs(lu - ROAD_U) * m_per_u < ROAD_HALF_WIDTH_M) & (lv > ROAD_V[0]) & (lv < ROAD_V[1])] = BUILT_UP
    codes[(lu > 0.9) & (lv < 0.05)] = NODATA
    landcover = folder / "landcover.tif"
    with rasterio.open(landcover, "w", driver="GTiff", height=rows, width=cols, count=1, dtype="uint8", crs=utm,
                       transform=rasterio.Affine(d, 0.0, left, 0.0, -d, top), nodata=NODATA,
                       compress="deflate") as dst:
        dst.write(codes, 1)

    classes = folder / "classes.csv"
    labels = {TREES: "Tree cover", GRASS: "Grassland", BUILT_UP: "Built-up", BARE: "Bare / sparse vegetation",
              WATER: "Permanent water bodies"}
    classes.write_text("code,ground,label\n" + "".join(f"{c},{g},{labels[c]}\n" for c, g in CLASSES.items()),
                       encoding="utf-8")
    return GeoScene(dem, landcover, classes, lonlat(*START_UV), lonlat(*GOAL_UV), lonlat(*LAKE_UV))
