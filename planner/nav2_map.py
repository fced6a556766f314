"""Nav2 maps: the obstacle layer as an occupancy map and an energy costmap as a raw-mode costmap (PGM + YAML).

Nav2's ``map_server`` loads a YAML file naming an 8-bit greyscale image (here a binary PGM,
``P5``), its ``resolution`` (m per cell) and the ``origin`` ``[x, y, yaw]`` of the image's
lower-left corner in the map frame. The image's first row is the *top* (north) edge, so the
map's rows (row 0 the southern edge) are written flipped.

- :func:`write_nav2_map` — ``mode: trinary``: occupied cells black (0), free cells 254,
  unknown cells 205, with thresholds under which Nav2 reads them back as exactly those
  three classes (:data:`NAV2_OCCUPIED_THRESH`, :data:`NAV2_FREE_THRESH`).
- :func:`write_nav2_costmap` — ``mode: raw``: a pixel value is the cost (0-100) Nav2
  puts in its occupancy grid: an energy costmap scaled so that 99 is the dearest finite
  cell, 100 (lethal) a blocked cell, 255 (read as unknown, -1) a cell whose energy is
  infinite. Use it as a static layer with ``trinary_costmap: false``.

:func:`read_nav2_map` reads either back and applies Nav2's loading rule.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from terrain import Grid, TerrainMap
from terrawatt_base.atomic import atomic_open, check_output_path, write_text_atomic
from terrawatt_base.checks import check_real, readonly
from terrawatt_base.errors import FileFormatError, GridMismatchError, InvalidParameterError

from .edge_cost import EnergyCost
from .energy_costmap import EnergyCostmap
from .ros_export import check_frame_origin

__all__ = [
    "NAV2_OCCUPIED_PIXEL",
    "NAV2_FREE_PIXEL",
    "NAV2_UNKNOWN_PIXEL",
    "NAV2_OCCUPIED_THRESH",
    "NAV2_FREE_THRESH",
    "NAV2_MODES",
    "Nav2Map",
    "write_nav2_map",
    "write_nav2_costmap",
    "read_nav2_map",
    "read_pgm",
    "nav2_map_paths",
]

#: Pixel of an occupied cell (black).
NAV2_OCCUPIED_PIXEL = 0
#: Pixel of a free cell (the value ``map_saver`` writes).
NAV2_FREE_PIXEL = 254
#: Pixel of an unknown cell (the value ``map_saver`` writes).
NAV2_UNKNOWN_PIXEL = 205
#: Occupancy (``1 - pixel / 255``) above which Nav2 reads a cell as occupied.
NAV2_OCCUPIED_THRESH = 0.65
#: Occupancy below which Nav2 reads a cell as free. 0.196, not map_saver's 0.25: the unknown
#: pixel 205 has occupancy 0.19608, which 0.25 would read as free.
NAV2_FREE_THRESH = 0.196
#: Image modes of a Nav2 map YAML.
NAV2_MODES = ("trinary", "scale", "raw")
#: Raw-mode costs of :func:`write_nav2_costmap`: the dearest finite cell, a blocked cell.
_TOP_COST, _LETHAL = 99, 100
_UNKNOWN_RAW = 255
#: A ``key: value`` line of a flat YAML file; a PGM header token (comments skipped).
_KEY = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)\s*:\s*(.*?)\s*$")
_PGM_TOKEN = re.compile(rb"\s*(?:#[^\n]*\n\s*)*(\S+)")


@dataclass(frozen=True)
class Nav2Map:
    """A Nav2 map read back: its image, where it lies, and the grid Nav2 would load.

    Attributes
    ----------
    pixels : ndarray of uint8, shape (rows, cols)
        The image in the map's row order (row 0 the southern edge: the PGM flipped back).
    grid : Grid
        ``resolution`` and the ``origin``'s x, y (the lower-left corner in the map frame).
    origin_yaw_rad : float
        The ``origin``'s yaw (0 for the maps written here).
    mode : str
        One of :data:`NAV2_MODES`.
    negate : bool
    occupied_thresh, free_thresh : float
    image : Path
        The image file, resolved beside the YAML.

    Derived: :attr:`occupancy` (Nav2's loading rule), :attr:`occupied`, :attr:`free`,
    :attr:`unknown`.
    """

    pixels: np.ndarray
    grid: Grid
    origin_yaw_rad: float
    mode: str
    negate: bool
    occupied_thresh: float
    free_thresh: float
    image: Path

    @property
    def occupancy(self) -> np.ndarray:
        """The ``nav_msgs/OccupancyGrid`` values Nav2's map_server loads (int8: 0-100, -1 unknown),
        in the map's row order.

        Trinary: 100 above ``occupied_thresh``, 0 below ``free_thresh``, else -1; scale: the
        same ends and a linear ramp between; raw: the pixel value, -1 above 100."""
        shade = self.pixels.astype(np.float64) / 255.0
        occ = shade if self.negate else 1.0 - shade
        if self.mode == "raw":
            return np.where(self.pixels <= 100, self.pixels, -1).astype(np.int8)
        if self.mode == "trinary":
            middle = np.full(occ.shape, -1.0)
        else:
            middle = np.rint((occ - self.free_thresh) / (self.occupied_thresh - self.free_thresh) * 100.0)
        out = np.where(occ > self.occupied_thresh, 100.0, np.where(occ < self.free_thresh, 0.0, middle))
        return out.astype(np.int8)

    @property
    def occupied(self) -> np.ndarray:
        """Cells Nav2 loads as occupied (100)."""
        return self.occupancy == 100

    @property
    def free(self) -> np.ndarray:
        """Cells Nav2 loads as free (0)."""
        return self.occupancy == 0

    @property
    def unknown(self) -> np.ndarray:
        """Cells Nav2 loads as unknown (-1)."""
        return self.occupancy == -1


def _yaml_number(value: float) -> str:
    """A float as YAML reads it back exactly (shortest round-trip repr, never ``-0.0``)."""
    return repr(float(value) + 0.0)


def nav2_map_paths(path: str | os.PathLike[str], name: str = "path") -> tuple[Path, Path]:
    """The YAML and the PGM files of a Nav2 map named by its YAML ``path``, checked before any work.

    Raises
    ------
    InvalidParameterError
        A name not ending in ``.yaml`` / ``.yml``; either file's path of the wrong kind (a folder); the message
        names ``name`` (as :func:`terrawatt_base.atomic.check_output_path`).
    """
    target = check_output_path(path, name)
    if target.suffix.lower() not in (".yaml", ".yml"):
        raise InvalidParameterError(f"{name}: a Nav2 map is named by its YAML file ('.yaml' or '.yml'), got "
                                    f"{str(target)!r}", parameter=name.strip("`"))
    return target, check_output_path(target.with_suffix(".pgm"), name)


def _write_pair(yaml_path: Path, pgm_path: Path, pixels: np.ndarray, grid: Grid, frame_origin_xy_m: Any, *,
                mode: str, comments: list[str]) -> Path:
    """The PGM (rows flipped: first row north), then the YAML that names it; each atomically."""
    fx, fy = check_frame_origin(frame_origin_xy_m, bounds=grid.bounds)
    rows, cols = pixels.shape
    header = f"P5\n# terrawatt {mode} map, first row north\n{cols} {rows}\n255\n".encode("ascii")
    with atomic_open(pgm_path, "wb") as fh:
        fh.write(header)
        fh.write(np.ascontiguousarray(pixels[::-1], dtype=np.uint8).tobytes())
    x0, y0 = grid.origin_xy_m
    lines = [f"# {c}" for c in comments] + [
        f"image: {pgm_path.name}",
        f"mode: {mode}",
        f"resolution: {_yaml_number(grid.cell_size_m)}",
        f"origin: [{_yaml_number(x0 - fx)}, {_yaml_number(y0 - fy)}, 0.0]",
        "negate: 0",
        f"occupied_thresh: {_yaml_number(NAV2_OCCUPIED_THRESH)}",
        f"free_thresh: {_yaml_number(NAV2_FREE_THRESH)}",
    ]
    return write_text_atomic(yaml_path, "\n".join(lines) + "\n")


def write_nav2_map(
    path: str | os.PathLike[str],
    tmap: TerrainMap,
    *,
    cost: EnergyCost | None = None,
    unknown: Any = None,
    frame_origin_xy_m: tuple[float, float] = (0.0, 0.0),
) -> Path:
    """Write a map's obstacle layer as a Nav2 occupancy map: ``path`` (YAML) and the PGM beside it.

    Occupied cells are black (0), free cells 254, ``unknown`` cells 205; the YAML says
    ``mode: trinary``, ``negate: 0``, the thresholds under which Nav2 reads exactly those
    three classes back, ``resolution`` the cell size and ``origin`` the map's lower-left
    corner in the map frame, yaw 0. The PGM is written first, then the YAML; each atomically.

    Parameters
    ----------
    path : path-like
        The YAML file (``.yaml`` / ``.yml``); the image is the same name with ``.pgm``.
    tmap : TerrainMap
        The map; its ``obstacle`` layer is the occupied cells.
    cost : EnergyCost, optional
        Edge costs on this map: its blocked cells (obstacles and cells steeper than its
        ``max_slope_rad``) are the occupied cells instead, as a planner that knows nothing of
        slopes needs them.
    unknown : array_like of bool, shape (rows, cols), optional
        Cells of unknown content (e.g. filled from DEM nodata); they take precedence.
    frame_origin_xy_m : (float, float)
        The map frame's origin in the map's coordinates: the YAML's origin is the map's
        lower-left corner minus it. Default: the map frame is the map's coordinates. Any other
        origin must lie within :data:`~planner.ros_export.MAX_FRAME_ORIGIN_DISTANCE_M` of the
        map's bounds (:func:`~planner.ros_export.check_frame_origin`).

    Returns
    -------
    Path
        The YAML file.

    Raises
    ------
    InvalidParameterError
        A path not ending in ``.yaml`` / ``.yml`` or a folder; not a TerrainMap; ``unknown``
        of another shape or not boolean; a frame origin not finite or farther than
        :data:`~planner.ros_export.MAX_FRAME_ORIGIN_DISTANCE_M` from the map.
    GridMismatchError
        ``cost`` priced on another grid.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from terrain import wall_map
    >>> folder = tempfile.TemporaryDirectory()
    >>> yaml_path = write_nav2_map(pathlib.Path(folder.name) / "wall.yaml", wall_map((6, 5), wall_col=2))
    >>> back = read_nav2_map(yaml_path)
    >>> bool((back.occupied == wall_map((6, 5), wall_col=2).obstacle).all())
    True
    >>> folder.cleanup()
    """
    yaml_path, pgm_path = nav2_map_paths(path)
    if not isinstance(tmap, TerrainMap):
        raise InvalidParameterError(f"tmap must be a TerrainMap, got {type(tmap).__name__!r}")
    occupied = np.asarray(tmap.obstacle, dtype=bool)
    source = "obstacle layer"
    if cost is not None:
        if not isinstance(cost, EnergyCost):
            raise InvalidParameterError(f"cost must be an EnergyCost or None, got {type(cost).__name__!r}")
        tmap.grid.check_same(cost.terrain.grid, "cost")
        occupied = np.asarray(cost.blocked, dtype=bool)
        source = f"obstacles and slopes above {math.degrees(cost.max_slope_rad):g} deg"
    pixels = np.where(occupied, NAV2_OCCUPIED_PIXEL, NAV2_FREE_PIXEL).astype(np.uint8)
    if unknown is not None:
        mask = np.asarray(unknown)
        if mask.dtype != bool:
            raise InvalidParameterError(f"unknown must be a boolean array, got dtype {mask.dtype}")
        if mask.shape != tmap.shape:
            raise GridMismatchError(f"unknown has shape {mask.shape!r}; the map has {tmap.shape!r}")
        pixels[mask] = NAV2_UNKNOWN_PIXEL
    comments = [f"terrawatt occupancy map: occupied = {source}; crs {tmap.crs or 'none (local metres)'}"]
    return _write_pair(yaml_path, pgm_path, pixels, tmap.grid, frame_origin_xy_m, mode="trinary", comments=comments)


def write_nav2_costmap(
    path: str | os.PathLike[str],
    costmap: EnergyCostmap,
    *,
    top_j_per_m: float | None = None,
    frame_origin_xy_m: tuple[float, float] = (0.0, 0.0),
) -> Path:
    """Write an energy costmap as a Nav2 raw-mode map: ``path`` (YAML) and the PGM beside it.

    A cell's pixel is its cost: ``round(99 * J/m / top_j_per_m)`` clipped to 0-99
    (proportional to energy, so costs add up like energies), 100 (lethal) for a blocked cell
    and 255 (Nav2 reads -1, unknown) for a cell of infinite energy. The YAML says
    ``mode: raw``; a comment gives the scale in J/m per cost unit. Load it as a Nav2 static
    layer with ``trinary_costmap: false`` to keep the costs.

    Parameters
    ----------
    path : path-like
        The YAML file (``.yaml`` / ``.yml``); the image is the same name with ``.pgm``.
    costmap : EnergyCostmap
    top_j_per_m : float, optional
        Energy per metre that costs 99 (> 0). Default: the costmap's dearest finite cell.
    frame_origin_xy_m : (float, float)
        The map frame's origin in the map's coordinates (as :func:`write_nav2_map`).

    Returns
    -------
    Path
        The YAML file.

    Raises
    ------
    InvalidParameterError
        A bad path; not an EnergyCostmap; ``top_j_per_m`` not finite and > 0; a frame origin
        not finite or farther than :data:`~planner.ros_export.MAX_FRAME_ORIGIN_DISTANCE_M` from the map.
    """
    yaml_path, pgm_path = nav2_map_paths(path)
    if not isinstance(costmap, EnergyCostmap):
        raise InvalidParameterError(f"costmap must be an EnergyCostmap, got {type(costmap).__name__!r}")
    values = costmap.energy_per_metre_j
    finite = np.isfinite(values)
    if top_j_per_m is None:
        top = float(values[finite].max()) if finite.any() else 1.0
        top = top if top > 0 else 1.0
    else:
        top = check_real("top_j_per_m", top_j_per_m, low=0.0, low_inclusive=False)
    scaled = np.clip(np.rint(np.where(finite, values, 0.0) * (_TOP_COST / top)), 0, _TOP_COST)
    pixels = np.where(finite, scaled, np.where(np.isnan(values), _LETHAL, _UNKNOWN_RAW)).astype(np.uint8)
    comments = [
        f"terrawatt energy costmap ({costmap.statistic} J per horizontal metre over headings at "
        f"{costmap.speed_mps:g} m/s): cost = round({_TOP_COST} * J/m / {_yaml_number(top)}), clipped to 0-{_TOP_COST}",
        f"one cost unit = {_yaml_number(top / _TOP_COST)} J/m; {_LETHAL} = blocked; {_UNKNOWN_RAW} (unknown) = infinite "
        "energy; load as a static layer with trinary_costmap: false",
    ]
    return _write_pair(yaml_path, pgm_path, pixels, costmap.grid, frame_origin_xy_m, mode="raw", comments=comments)


def read_pgm(path: str | os.PathLike[str]) -> np.ndarray:
    """The pixels of a binary 8-bit PGM (``P5``, maxval <= 255) as uint8, in file order (first row at the top).

    Raises
    ------
    FileFormatError
        Not a P5 PGM with maxval <= 255, or truncated.
    """
    data = Path(path).read_bytes()
    tokens: list[bytes] = []
    pos = 0
    while len(tokens) < 4:
        match = _PGM_TOKEN.match(data, pos)
        if match is None:
            raise FileFormatError(f"{str(path)!r} is not a PGM image: its header ends early")
        tokens.append(match.group(1))
        pos = match.end()
    if tokens[0] != b"P5":
        raise FileFormatError(f"{str(path)!r} is not a binary PGM (magic {tokens[0][:8]!r}, expected b'P5')")
    try:
        cols, rows, maxval = (int(t) for t in tokens[1:])
    except ValueError as exc:
        raise FileFormatError(f"{str(path)!r} has a malformed PGM header {tokens!r}") from exc
    if not (cols > 0 and rows > 0 and 0 < maxval <= 255):
        raise FileFormatError(f"{str(path)!r}: PGM of {cols} x {rows} pixels, maxval {maxval}; expected 8-bit")
    pos += 1  # the single whitespace byte after maxval
    body = data[pos:pos + rows * cols]
    if len(body) != rows * cols:
        raise FileFormatError(f"{str(path)!r} is truncated: {len(body)} of {rows * cols} pixel bytes")
    return np.frombuffer(body, dtype=np.uint8).reshape(rows, cols).copy()


def _yaml_value(text: str) -> Any:
    """A flat YAML value: a number, a ``[a, b, c]`` list of numbers, or a (quoted) string; a trailing
    `` # comment`` dropped."""
    if text[:1] in ("'", '"') and text.find(text[0], 1) > 0:
        return text[1:text.find(text[0], 1)]
    text = text.split(" #", 1)[0].strip()
    if text.startswith("[") and text.endswith("]"):
        return [_yaml_value(part.strip()) for part in text[1:-1].split(",")]
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def _flat_yaml(path: Path) -> dict[str, Any]:
    """The ``key: value`` lines of a flat YAML file (Nav2's map files), comments skipped."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError as exc:
        raise FileFormatError(f"{str(path)!r} is not a UTF-8 YAML file") from exc
    out: dict[str, Any] = {}
    for number, line in enumerate(lines, 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        match = _KEY.match(line)
        if match is None:
            raise FileFormatError(f"{str(path)!r} line {number}: {line[:60]!r} is not a flat 'key: value' line")
        out[match.group(1)] = _yaml_value(match.group(2))
    return out


def read_nav2_map(path: str | os.PathLike[str]) -> Nav2Map:
    """Read a Nav2 map (the YAML and the PGM it names) into the map's row order.

    Raises
    ------
    FileFormatError
        A YAML without ``image``, ``resolution``, ``origin`` ``[x, y, yaw]``, ``negate``,
        ``occupied_thresh`` or ``free_thresh``, or of an unknown ``mode``; an image that is
        not an 8-bit binary PGM.
    """
    yaml_path = Path(path)
    fields = _flat_yaml(yaml_path)
    missing = [k for k in ("image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh")
               if k not in fields]
    if missing:
        raise FileFormatError(f"{str(yaml_path)!r} is not a Nav2 map YAML: it lacks {missing!r}")
    origin, mode = fields["origin"], fields.get("mode", "trinary")
    numbers = (fields["resolution"], fields["occupied_thresh"], fields["free_thresh"])
    if not (isinstance(origin, list) and len(origin) == 3 and all(isinstance(v, (int, float)) for v in origin)):
        raise FileFormatError(f"{str(yaml_path)!r}: origin must be [x, y, yaw], got {origin!r}")
    if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in numbers):
        raise FileFormatError(f"{str(yaml_path)!r}: resolution and thresholds must be numbers, got {numbers!r}")
    if mode not in NAV2_MODES or fields["negate"] not in (0, 1):
        raise FileFormatError(f"{str(yaml_path)!r}: mode {mode!r} / negate {fields['negate']!r}; expected one of "
                              f"{NAV2_MODES!r} and 0 or 1")
    image = Path(str(fields["image"]))
    image = image if image.is_absolute() else yaml_path.parent / image
    pixels = read_pgm(image)[::-1]
    try:
        grid = Grid(pixels.shape, float(fields["resolution"]), (float(origin[0]), float(origin[1])))
    except InvalidParameterError as exc:
        raise FileFormatError(f"{str(yaml_path)!r} describes no valid grid: {exc}") from exc
    return Nav2Map(readonly(pixels), grid, float(origin[2]), mode, bool(fields["negate"]),
                   float(fields["occupied_thresh"]), float(fields["free_thresh"]), image)
