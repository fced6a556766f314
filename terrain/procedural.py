"""Seeded procedural maps for examples and tests, exact flat/ramp/wall maps, and the bundled example map."""

from __future__ import annotations

from collections.abc import Sequence
from importlib import resources
from numbers import Integral

import numpy as np
import scipy.fft
from scipy import ndimage

from terrawatt_base.checks import check_int, check_real, check_seed, check_shape, check_text
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from .terrain_map import UNKNOWN_GROUND, TerrainMap

__all__ = [
    "procedural_map",
    "flat_map",
    "ramp_map",
    "wall_map",
    "example_map",
    "EXAMPLE_START_XY_M",
    "EXAMPLE_GOAL_XY_M",
]

#: Suggested start of a route on :func:`example_map` (world coordinates, m).
EXAMPLE_START_XY_M = (10.0, 10.0)
#: Suggested goal of a route on :func:`example_map` (world coordinates, m).
EXAMPLE_GOAL_XY_M = (150.0, 150.0)

_EXAMPLE_RESOURCE = "example_map.npz"


# ------------------------------------------------------------------ validation
def _positive(name: str, value: float) -> float:
    return check_real(name, value, low=0.0, low_inclusive=False)


def _check_grounds(grounds: Sequence[str]) -> tuple[str, ...]:
    if isinstance(grounds, str):
        raise InvalidParameterError(f"grounds must be a sequence of names, got the string {grounds!r}")
    names = tuple(grounds)
    if any(not isinstance(n, str) or not n for n in names) or len(set(names)) != len(names):
        raise InvalidParameterError(f"grounds must be unique non-empty names, got {grounds!r}")
    return names


def _single_ground(shape: tuple[int, int], ground: str | None) -> dict:
    """``ground``/``ground_names`` keyword arguments for a map covered by one ground."""
    if ground is None:
        return {}
    check_text("ground", ground)
    return {"ground": np.zeros(shape, np.int16), "ground_names": {0: ground}}


# -------------------------------------------------------------- exact builders
def flat_map(
    shape: Sequence[int] = (32, 32),
    cell_size_m: float = 1.0,
    *,
    elevation_m: float = 0.0,
    ground: str | None = "asphalt",
    origin_xy_m: tuple[float, float] = (0.0, 0.0),
) -> TerrainMap:
    """A level map at one elevation, covered by one ground, without obstacles.

    Parameters
    ----------
    shape : (int, int)
        ``(rows, cols)``, each >= 2.
    cell_size_m : float
        Cell side (m).
    elevation_m : float
        Elevation of every cell (m).
    ground : str or None
        Name of the ground covering the map (class id 0); ``None`` leaves it unknown (-1).
    origin_xy_m : (float, float)
        Lower-left corner of the map (m).

    Returns
    -------
    TerrainMap

    Raises
    ------
    InvalidParameterError
        Bad shape, cell size, elevation or ground name.

    Examples
    --------
    >>> from terrain import flat_map
    >>> tmap = flat_map((4, 6), 0.5)
    >>> tmap.bounds, tmap.ground_names, float(tmap.slope_rad.max())
    ((0.0, 0.0, 3.0, 2.0), {0: 'asphalt'}, 0.0)
    """
    shape = check_shape("shape", shape, low=2)
    elevation_m = check_real("elevation_m", elevation_m)
    return TerrainMap(
        np.full(shape, elevation_m), cell_size_m, origin_xy_m, **_single_ground(shape, ground)
    )


def ramp_map(
    shape: Sequence[int] = (32, 32),
    cell_size_m: float = 1.0,
    grade: float = 0.1,
    axis: str = "x",
    *,
    ground: str | None = "asphalt",
    origin_xy_m: tuple[float, float] = (0.0, 0.0),
) -> TerrainMap:
    """A plane rising with a constant grade along +x or +y.

    Elevation is ``grade * (x - x0)`` (or ``grade * (y - y0)``) at each cell centre, so
    ``grad_x`` (or ``grad_y``) equals ``grade`` everywhere and the slope is
    ``arctan(|grade|)``.

    Parameters
    ----------
    shape : (int, int)
        ``(rows, cols)``, each >= 2.
    cell_size_m : float
        Cell side (m).
    grade : float
        Rise per metre (dz/dl, dimensionless, ``tan`` of the slope angle); negative falls.
    axis : {"x", "y"}
        Direction along which the map rises.
    ground : str or None
        Ground name of the whole map (class id 0); ``None`` leaves it unknown.
    origin_xy_m : (float, float)
        Lower-left corner of the map (m).

    Returns
    -------
    TerrainMap

    Raises
    ------
    InvalidParameterError
        Bad shape, cell size, grade or ground name.
    UnknownNameError
        ``axis`` not ``"x"`` or ``"y"``.

    Examples
    --------
    >>> from terrain import ramp_map
    >>> tmap = ramp_map((3, 4), cell_size_m=2.0, grade=0.25)
    >>> tmap.elevation_m[0].tolist()
    [0.25, 0.75, 1.25, 1.75]
    >>> float(tmap["grad_x"][1, 2]), float(tmap["grad_y"][1, 2])
    (0.25, 0.0)
    """
    shape = check_shape("shape", shape, low=2)
    grade = check_real("grade", grade)
    if axis not in ("x", "y"):
        raise UnknownNameError(f"axis must be 'x' or 'y', got {axis!r}")
    cell = _positive("cell_size_m", cell_size_m)
    rows, cols = shape
    if axis == "x":
        elev = np.broadcast_to(grade * (np.arange(cols) + 0.5) * cell, shape)
    else:
        elev = np.broadcast_to(grade * (np.arange(rows) + 0.5)[:, None] * cell, shape)
    return TerrainMap(elev, cell, origin_xy_m, **_single_ground(shape, ground))


def wall_map(
    shape: Sequence[int] = (40, 40),
    cell_size_m: float = 1.0,
    *,
    wall_col: int | None = None,
    gap_rows: tuple[int, int] | None = None,
    ground: str | None = "asphalt",
    origin_xy_m: tuple[float, float] = (0.0, 0.0),
) -> TerrainMap:
    """A flat map split by a one-cell-thick obstacle wall along a column, with one gap.

    Parameters
    ----------
    shape : (int, int)
        ``(rows, cols)``, each >= 2.
    cell_size_m : float
        Cell side (m).
    wall_col : int, optional
        Column of the wall; defaults to ``cols // 2``.
    gap_rows : (int, int), optional
        Half-open row range ``[start, stop)`` left open in the wall. Defaults to
        ``start = 3 * rows // 4`` and ``stop = start + max(2, rows // 10)`` (clipped to the
        map), i.e. a gap near the top; ``(0, 0)`` gives a closed wall.
    ground : str or None
        Ground name of the whole map (class id 0); ``None`` leaves it unknown.
    origin_xy_m : (float, float)
        Lower-left corner of the map (m).

    Returns
    -------
    TerrainMap

    Raises
    ------
    InvalidParameterError
        Bad shape, cell size, wall column or gap rows.

    Examples
    --------
    >>> from terrain import wall_map
    >>> tmap = wall_map((10, 6), wall_col=2, gap_rows=(7, 9))
    >>> tmap.obstacle[:, 2].astype(int).tolist()
    [1, 1, 1, 1, 1, 1, 1, 0, 0, 1]
    >>> int(tmap.obstacle.sum())
    8
    """
    shape = check_shape("shape", shape, low=2)
    rows, cols = shape
    if wall_col is None:
        wall_col = cols // 2
    wall_col = check_int("wall_col", wall_col, low=0, high=cols - 1)
    if gap_rows is None:
        start = 3 * rows // 4
        gap_rows = (start, min(rows, start + max(2, rows // 10)))
    try:
        start, stop = gap_rows
        valid = all(isinstance(v, Integral) and not isinstance(v, bool) for v in (start, stop))
    except (TypeError, ValueError):
        valid = False
    if not valid or not 0 <= start <= stop <= rows:
        raise InvalidParameterError(
            f"gap_rows must be integers (start, stop) with 0 <= start <= stop <= {rows}, got {gap_rows!r}"
        )
    obstacle = np.zeros(shape, bool)
    obstacle[:, wall_col] = True
    obstacle[start:stop, wall_col] = False
    return TerrainMap(
        np.zeros(shape), cell_size_m, origin_xy_m, obstacle=obstacle, **_single_ground(shape, ground)
    )


# ----------------------------------------------------------------- procedural
def _smooth_noise(rng: np.random.Generator, shape: tuple[int, int], sigma_cells: float) -> np.ndarray:
    """Zero-mean, unit-std white noise low-pass filtered by a Gaussian (periodic, via FFT)."""
    spectrum = scipy.fft.rfft2(rng.standard_normal(shape))
    field = scipy.fft.irfft2(ndimage.fourier_gaussian(spectrum, sigma_cells, n=shape[1]), s=shape)
    field -= field.mean()
    std = field.std()
    return field / std if std > 0 else field


def _segment_distance(
    x: np.ndarray, y: np.ndarray, a: np.ndarray, b: np.ndarray
) -> np.ndarray:
    """Distance (m) from points ``(x, y)`` (broadcastable) to the segment ``a``-``b``."""
    ab = b - a
    t = np.clip(((x - a[0]) * ab[0] + (y - a[1]) * ab[1]) / float(ab @ ab), 0.0, 1.0)
    return np.hypot(x - (a[0] + t * ab[0]), y - (a[1] + t * ab[1]))


def _random_segment(rng: np.random.Generator, extent_xy_m: np.ndarray, length_m: float) -> np.ndarray:
    """Endpoints ``(2, 2)`` of a segment of ``length_m`` centred in the middle 60 % of the map."""
    centre = extent_xy_m * rng.uniform(0.2, 0.8, size=2)
    angle = rng.uniform(0.0, np.pi)
    half = 0.5 * length_m * np.array([np.cos(angle), np.sin(angle)])
    return np.stack([centre - half, centre + half])


def procedural_map(
    shape: Sequence[int] = (256, 256),
    cell_size_m: float = 1.0,
    seed: int | None = 0,
    *,
    origin_xy_m: tuple[float, float] = (0.0, 0.0),
    n_hills: int = 6,
    hill_size_m: float | None = None,
    slope_deg: float = 8.0,
    n_ridges: int = 1,
    ridge_height_m: float | None = None,
    ridge_slope_deg: float = 20.0,
    grounds: Sequence[str] = ("asphalt", "grass", "sand", "snow"),
    ground_patch_size_m: float | None = None,
    obstacle_fraction: float = 0.01,
    rock_radius_m: float | None = None,
    n_walls: int = 0,
) -> TerrainMap:
    """A seeded random map with hills, ridges, ground patches and obstacles.

    The elevation is the sum of

    - ``n_hills`` Gaussian hills (random centres, radii ``0.6-1.4 * hill_size_m``) plus
      gentle undulations (Gaussian-filtered noise), scaled together so that 95 % of cells
      are less steep than ``slope_deg``;
    - ``n_ridges`` straight ridges of height ``ridge_height_m`` with a Gaussian cross
      profile whose steepest flanks reach ``ridge_slope_deg`` (the few steep parts).

    Ground classes ``0 .. len(grounds) - 1`` (named by ``grounds``) form contiguous
    patches about ``ground_patch_size_m`` across (the class whose smoothed noise field is
    largest wins each cell). Obstacles are round rocks covering at least
    ``obstacle_fraction`` of the cells, plus ``n_walls`` straight walls, each with a gap.

    Each component draws from its own child of ``numpy.random.SeedSequence(seed)``, so the
    same seed gives the same map and, for example, changing ``obstacle_fraction`` leaves
    the elevation and grounds unchanged. Lengths default to fractions of the map's shorter
    side ``L``, so maps of any extent look alike.

    Parameters
    ----------
    shape : (int, int)
        ``(rows, cols)``, each >= 2.
    cell_size_m : float
        Cell side (m).
    seed : int or None
        Seed, an integer in ``[0, 2**32)`` (the library's seed rule); ``None`` draws fresh
        entropy, so each call gives another map.
    origin_xy_m : (float, float)
        Lower-left corner of the map (m).
    n_hills : int
        Number of Gaussian hills.
    hill_size_m : float, optional
        Typical hill radius (Gaussian sigma, m); default ``L / 10``. Also sets the
        undulation scale (half of it).
    slope_deg : float
        95th-percentile slope of hills and undulations (deg, in [0, 60]).
    n_ridges : int
        Number of ridges.
    ridge_height_m : float, optional
        Ridge height (m); default ``L / 80``.
    ridge_slope_deg : float
        Steepest slope on a ridge flank (deg, in (0, 80]).
    grounds : sequence of str
        Ground names; empty leaves every cell unknown (-1).
    ground_patch_size_m : float, optional
        Scale of the ground patches (m); default ``L / 6``.
    obstacle_fraction : float
        Minimum fraction of cells covered by rocks, in [0, 0.5].
    rock_radius_m : float, optional
        Typical rock radius (m), at least ``cell_size_m``; default
        ``max(L / 100, cell_size_m)``; radii vary ``0.6-1.4`` times this.
    n_walls : int
        Number of straight walls (length ``0.3 L``, about 1.5 cells thick, gap of ``L / 20``).

    Returns
    -------
    TerrainMap

    Raises
    ------
    InvalidParameterError
        Any parameter out of range.

    Examples
    --------
    >>> import numpy as np
    >>> from terrain import procedural_map
    >>> tmap = procedural_map((64, 64), cell_size_m=0.5, seed=3)
    >>> tmap.shape, sorted(tmap.ground_names.values())
    ((64, 64), ['asphalt', 'grass', 'sand', 'snow'])
    >>> bool(np.percentile(np.degrees(tmap.slope_rad), 50) < 15)
    True
    >>> bool(np.array_equal(tmap.elevation_m, procedural_map((64, 64), 0.5, seed=3).elevation_m))
    True
    """
    shape = check_shape("shape", shape, low=2)
    cell = _positive("cell_size_m", cell_size_m)
    seed = check_seed(seed)
    n_hills, n_ridges, n_walls = (check_int(k, v, low=0) for k, v in
                                  (("n_hills", n_hills), ("n_ridges", n_ridges), ("n_walls", n_walls)))
    slope_deg = check_real("slope_deg", slope_deg, low=0.0, high=60.0)
    ridge_slope_deg = check_real("ridge_slope_deg", ridge_slope_deg, low=0.0, low_inclusive=False, high=80.0)
    obstacle_fraction = check_real("obstacle_fraction", obstacle_fraction, low=0.0, high=0.5)
    grounds = _check_grounds(grounds)
    rows, cols = shape
    side_m = min(rows, cols) * cell
    hill_size_m = side_m / 10 if hill_size_m is None else _positive("hill_size_m", hill_size_m)
    ground_patch_size_m = side_m / 6 if ground_patch_size_m is None else _positive(
        "ground_patch_size_m", ground_patch_size_m
    )
    ridge_height_m = check_real("ridge_height_m", side_m / 80 if ridge_height_m is None else ridge_height_m, low=0.0)
    if rock_radius_m is None:
        rock_radius_m = max(side_m / 100, cell)
    elif check_real("rock_radius_m", rock_radius_m, low=0.0) < cell:
        raise InvalidParameterError(
            f"rock_radius_m must be at least the cell size {cell!r} m, got {rock_radius_m!r}"
        )

    hill_rng, ridge_rng, ground_rng, rock_rng, wall_rng = (
        np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(5)
    )
    xs = (np.arange(cols) + 0.5) * cell  # cell centres relative to the origin
    ys = (np.arange(rows) + 0.5) * cell
    extent = np.array([cols * cell, rows * cell])

    # Hills and undulations, scaled to the requested 95th-percentile slope.
    smooth = np.zeros(shape)
    for _ in range(n_hills):
        cx, cy = extent * hill_rng.uniform(0.0, 1.0, size=2)
        sigma = hill_size_m * hill_rng.uniform(0.6, 1.4)
        height = hill_rng.uniform(0.5, 1.0)
        bump_y = np.exp(-0.5 * ((ys - cy) / sigma) ** 2)
        bump_x = np.exp(-0.5 * ((xs - cx) / sigma) ** 2)
        smooth += height * np.outer(bump_y, bump_x)
    smooth += 0.15 * _smooth_noise(hill_rng, shape, 0.5 * hill_size_m / cell)
    gy, gx = np.gradient(smooth, cell)
    p95 = np.percentile(np.hypot(gx, gy), 95)
    elevation = smooth * (np.tan(np.radians(slope_deg)) / p95) if p95 > 0 else np.zeros(shape)

    # Ridges: Gaussian cross profile with the steepest flank at ridge_slope_deg.
    if n_ridges and ridge_height_m > 0:
        width_m = ridge_height_m * np.exp(-0.5) / np.tan(np.radians(ridge_slope_deg))
        for _ in range(n_ridges):
            ends = _random_segment(ridge_rng, extent, side_m * ridge_rng.uniform(0.4, 0.8))
            dist = _segment_distance(xs[None, :], ys[:, None], ends[0], ends[1])
            elevation += ridge_height_m * np.exp(-0.5 * (dist / width_m) ** 2)

    # Ground patches: the class whose smoothed noise is largest wins the cell.
    if grounds:
        ground = np.zeros(shape, np.int16)
        best = _smooth_noise(ground_rng, shape, ground_patch_size_m / cell / 2)
        for k in range(1, len(grounds)):
            field = _smooth_noise(ground_rng, shape, ground_patch_size_m / cell / 2)
            wins = field > best
            ground[wins] = k
            np.maximum(best, field, out=best)
    else:
        ground = np.full(shape, UNKNOWN_GROUND, np.int16)

    # Rocks: discs drawn until they cover the requested fraction.
    obstacle = np.zeros(shape, bool)
    target = int(np.ceil(obstacle_fraction * rows * cols))
    covered = 0
    while covered < target:
        cx, cy = extent * rock_rng.uniform(0.0, 1.0, size=2)
        radius = rock_radius_m * rock_rng.uniform(0.6, 1.4)
        c0, c1 = np.searchsorted(xs, [cx - radius, cx + radius])
        r0, r1 = np.searchsorted(ys, [cy - radius, cy + radius])
        disc = np.hypot(xs[None, c0:c1] - cx, ys[r0:r1, None] - cy) <= radius
        patch = obstacle[r0:r1, c0:c1]
        covered += int(np.count_nonzero(disc & ~patch))
        patch |= disc

    # Walls: thick segments with a gap in the middle.
    for _ in range(n_walls):
        ends = _random_segment(wall_rng, extent, 0.3 * side_m)
        dist = _segment_distance(xs[None, :], ys[:, None], ends[0], ends[1])
        mid = ends.mean(axis=0)
        in_gap = np.hypot(xs[None, :] - mid[0], ys[:, None] - mid[1]) < max(side_m / 40, cell)
        obstacle |= (dist <= 0.75 * cell) & ~in_gap

    return TerrainMap(
        elevation,
        cell,
        origin_xy_m,
        ground=ground,
        ground_names=dict(enumerate(grounds)),
        obstacle=obstacle,
    )


# ---------------------------------------------------------------- bundled map
def example_map() -> TerrainMap:
    """The small example map bundled with terrawatt (160 x 160 cells of 1 m).

    Hills, a ridge, asphalt / grass / sand / snow patches and a few rocks, built by
    ``examples/make_example_map.py``. Between :data:`EXAMPLE_START_XY_M` ``(10, 10)`` and
    :data:`EXAMPLE_GOAL_XY_M` ``(150, 150)`` a hill and a sand patch sit on the straight
    line, so the minimum-energy route bends away from it.

    Returns
    -------
    TerrainMap

    Examples
    --------
    >>> from terrain import example_map
    >>> tmap = example_map()
    >>> tmap.shape, tmap.cell_size_m
    ((160, 160), 1.0)
    """
    with resources.as_file(resources.files(__package__) / "data" / _EXAMPLE_RESOURCE) as path:
        return TerrainMap.load(path)
