"""Build the example map bundled as terrain/data/example_map.npz (run this script to regenerate it).

The map is 160 x 160 cells of 1 m (origin (0, 0), no CRS) and is loaded with
``terrain.example_map()``. The suggested route runs from start (10, 10) m to goal
(150, 150) m (``terrain.EXAMPLE_START_XY_M`` / ``terrain.EXAMPLE_GOAL_XY_M``).

What is on it (all positions in metres):

- gentle seeded undulations (``procedural_map`` with seed 7, slopes of a few degrees);
- a hill 6 m high (Gaussian, sigma 16 m, flanks up to about 13 deg) centred at (82, 78),
  right on the straight line from start to goal;
- a ridge 3 m high with 20 deg flanks from (100, 15) to (150, 60);
- grounds: grass everywhere, an 8 m wide asphalt road from the start north to (10, 105),
  bending to (40, 135) and running east to (158, 135); a sand patch (radius 16 m) at
  (112, 110) and a snow patch (radius 18 m) at (60, 150) off the line (the goal lies 15 m
  north of the road);
- seven round rocks (obstacles, radius 2-3 m), none on the road, the start or the goal.

The straight route climbs the hill and crosses the sand; a minimum-energy route
follows the road (or at least skirts the hill and the sand), so the two differ visibly.
Elevations are rounded to 1/1024 m so that the compressed file stays small.

Usage: ``python examples/make_example_map.py [--out PATH]``; by default it overwrites the
bundled file beside the ``terrain`` package of this repository.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import shapely
from shapely import LineString, Point

from terrain import (
    EXAMPLE_GOAL_XY_M,
    EXAMPLE_START_XY_M,
    TerrainMap,
    procedural_map,
    set_ground_from_polygons,
    set_obstacles_from_polygons,
)

SHAPE = (160, 160)
CELL_SIZE_M = 1.0
ROCKS_XY_RADIUS_M = [
    (60.0, 30.0, 2.5),
    (30.0, 62.0, 2.0),
    (126.0, 86.0, 3.0),
    (98.0, 146.0, 2.0),
    (72.0, 112.0, 2.5),
    (140.0, 110.0, 2.0),
    (45.0, 90.0, 2.0),
]


def _gaussian_hill(x: np.ndarray, y: np.ndarray, centre: tuple[float, float], sigma_m: float) -> np.ndarray:
    return np.exp(-0.5 * ((x - centre[0]) ** 2 + (y - centre[1]) ** 2) / sigma_m**2)


def build_example_map() -> TerrainMap:
    """The example map described in this module's docstring (deterministic)."""
    base = procedural_map(
        SHAPE, CELL_SIZE_M, seed=7, n_hills=0, slope_deg=2.0, n_ridges=0, grounds=(), obstacle_fraction=0.0
    )
    xs, ys = base.cell_centres()
    x, y = np.meshgrid(xs, ys)
    elevation = base.elevation_m - base.elevation_m.min()
    elevation = elevation + 6.0 * _gaussian_hill(x, y, (82.0, 78.0), 16.0)
    ridge = LineString([(100.0, 15.0), (150.0, 60.0)])
    ridge_height_m, ridge_slope_rad = 3.0, np.radians(20.0)
    ridge_sigma_m = ridge_height_m * np.exp(-0.5) / np.tan(ridge_slope_rad)
    dist_m = shapely.distance(ridge, shapely.points(x, y))
    elevation += ridge_height_m * np.exp(-0.5 * (dist_m / ridge_sigma_m) ** 2)
    elevation = np.round(elevation * 1024.0) / 1024.0

    tmap = TerrainMap(
        elevation,
        CELL_SIZE_M,
        ground=np.zeros(SHAPE, np.int16),
        ground_names={0: "grass"},
    )
    road = LineString([(10.0, 0.0), (10.0, 105.0), (40.0, 135.0), (158.0, 135.0)]).buffer(4.0)
    tmap = set_ground_from_polygons(
        tmap,
        {
            "asphalt": road,
            "sand": Point(112.0, 110.0).buffer(16.0),
            "snow": Point(60.0, 150.0).buffer(18.0),
        },
    )
    rocks = [Point(px, py).buffer(r) for px, py, r in ROCKS_XY_RADIUS_M]
    tmap = set_obstacles_from_polygons(tmap, rocks)
    for name, xy in (("start", EXAMPLE_START_XY_M), ("goal", EXAMPLE_GOAL_XY_M)):
        if tmap.sample("obstacle", *xy):
            raise RuntimeError(f"the example {name} {xy!r} lies on an obstacle")
    return tmap


def main(argv: list[str] | None = None) -> int:
    """Build the map and save it (default: the bundled file of this repository)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = Path(__file__).resolve().parents[1] / "terrain" / "data" / "example_map.npz"
    parser.add_argument("--out", type=Path, default=default, help="output .npz file")
    args = parser.parse_args(argv)
    path = build_example_map().save(args.out)
    print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
