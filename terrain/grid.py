"""Grid: the georeferencing value object shared by everything that lives on a raster.

A :class:`Grid` is a shape, a square cell size and an origin, and nothing else: the map
(:class:`~terrain.terrain_map.TerrainMap`), the per-cell model registry and the planner's
edge-cost tables all hold one and convert between cells and metres through it, so the
convention below is written once.

Convention: ``origin_xy_m`` is the lower-left (south-west) corner of cell ``(0, 0)``. Row
index grows with ``y`` (north), column index with ``x`` (east); arrays are indexed
``[row, col]``. Cell ``(r, c)`` covers ``x in [x0 + c*d, x0 + (c+1)*d)``,
``y in [y0 + r*d, y0 + (r+1)*d)``; points on the far edges belong to the last row/column.

In rasterio's terms (an :class:`affine.Affine` maps ``(col, row)`` to the ``(x, y)`` of a
cell's corner) the arrays' transform is :attr:`Grid.transform`, ``Affine(d, 0, x0, 0, d,
y0)``; a file holds them flipped, north row first, under :attr:`Grid.north_up_transform`,
``Affine(d, 0, x0, 0, -d, y_max)``. :meth:`Grid.from_transform` takes either.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from affine import Affine

from terrawatt_base.checks import check_int, check_real, fmt_number
from terrawatt_base.errors import GridMismatchError, InvalidParameterError, OutOfBoundsError

__all__ = ["Grid"]


@dataclass(frozen=True)
class Grid:
    """A georeferenced raster grid of square cells (immutable, hashable).

    Parameters
    ----------
    shape : (int, int)
        ``(rows, cols)``, each >= 1.
    cell_size_m : float
        Side of a cell in metres (finite, > 0).
    origin_xy_m : (float, float)
        World coordinates of the lower-left corner of cell (0, 0).

    Raises
    ------
    InvalidParameterError
        Non-integer or empty shape; a cell size that is not a finite positive number; an
        origin that is not finite; a grid whose far corner is not finite (e.g. 1e308 m cells).

    Examples
    --------
    >>> g = Grid((4, 5), 2.0, (10.0, 20.0))
    >>> g.bounds
    (10.0, 20.0, 20.0, 28.0)
    >>> g.rowcol(11.0, 27.9)
    (3, 0)
    >>> g.xy(3, 0)
    (11.0, 27.0)
    """

    shape: tuple[int, int]
    cell_size_m: float
    origin_xy_m: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        try:
            rows, cols = self.shape
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"shape must be (rows, cols), got {self.shape!r}") from exc
        shape = (check_int("shape[0]", rows, low=1), check_int("shape[1]", cols, low=1))
        cell = check_real("cell_size_m", self.cell_size_m, low=0.0, low_inclusive=False)
        try:
            ox, oy = self.origin_xy_m
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(f"origin_xy_m must be (x, y), got {self.origin_xy_m!r}") from exc
        origin = (check_real("origin_xy_m[0]", ox), check_real("origin_xy_m[1]", oy))
        far = (origin[0] + shape[1] * cell, origin[1] + shape[0] * cell)
        if not all(math.isfinite(v) for v in far):
            raise InvalidParameterError(
                f"a grid of {shape!r} cells of {cell!r} m from {origin!r} has no finite far corner; "
                "expected a cell size in metres"
            )
        object.__setattr__(self, "shape", shape)
        object.__setattr__(self, "cell_size_m", cell)
        object.__setattr__(self, "origin_xy_m", origin)

    @classmethod
    def from_bounds(cls, shape: tuple[int, int], bounds_m: tuple[float, float, float, float]) -> Grid:
        """The grid of ``shape`` cells that exactly covers ``(xmin, ymin, xmax, ymax)``.

        Raises
        ------
        InvalidParameterError
            If the bounds do not give square cells of positive size for ``shape``.
        """
        rows, cols = shape
        xmin, ymin, xmax, ymax = (check_real(f"bounds_m[{i}]", b) for i, b in enumerate(bounds_m))
        dx = (xmax - xmin) / cols
        dy = (ymax - ymin) / rows
        if not (dx > 0 and dy > 0) or not np.isclose(dx, dy, rtol=1e-9):
            raise InvalidParameterError(
                f"bounds_m {bounds_m!r} with shape {tuple(shape)!r} give cells of {dx!r} x {dy!r} m; "
                "expected square cells of positive size"
            )
        return cls((rows, cols), dx, (xmin, ymin))

    @classmethod
    def from_transform(cls, shape: tuple[int, int], transform: Affine) -> Grid:
        """The grid of ``shape`` cells under an affine transform (rasterio's convention).

        A north-up transform (``e < 0``, a file's: row 0 is the north row) and this
        package's south-up one (``e > 0``, :attr:`transform`) give the same grid; the caller
        flips a north-up array (``np.flipud``) to index it as this grid does.

        Raises
        ------
        InvalidParameterError
            A transform that is not an :class:`affine.Affine`, is rotated or sheared, or has
            cells that are not square.

        Examples
        --------
        >>> g = Grid((4, 5), 2.0, (10.0, 20.0))
        >>> Grid.from_transform(g.shape, g.north_up_transform) == g == Grid.from_transform(g.shape, g.transform)
        True
        """
        if not isinstance(transform, Affine):
            raise InvalidParameterError(f"transform must be an affine.Affine, got {type(transform).__name__!r}")
        a, b, c, d, e, f = transform[:6]
        if b != 0.0 or d != 0.0:
            raise InvalidParameterError(f"transform {tuple(transform[:6])!r} is rotated or sheared; expected a "
                                        "north-up or south-up grid")
        if not (a > 0 and math.isclose(abs(e), a, rel_tol=1e-9)):
            raise InvalidParameterError(f"transform {tuple(transform[:6])!r} has cells of {fmt_number(a)} x "
                                        f"{fmt_number(abs(e))}; expected square cells of positive size")
        rows = check_int("shape[0]", shape[0], low=1)
        return cls((rows, shape[1]), float(a), (float(c), float(f) if e > 0 else float(f + e * rows)))

    # ------------------------------------------------------------------ derived
    @property
    def transform(self) -> Affine:
        """The affine transform of this package's arrays (row 0 south): ``transform @ (col, row)`` is a cell's south-west corner.

        Examples
        --------
        >>> Grid((4, 5), 2.0, (10.0, 20.0)).transform @ (1, 3)
        (12.0, 26.0)
        """
        x0, y0 = self.origin_xy_m
        return Affine(self.cell_size_m, 0.0, x0, 0.0, self.cell_size_m, y0)

    @property
    def north_up_transform(self) -> Affine:
        """The transform of the arrays flipped north row first, as GeoTIFF files hold them (rasterio's usual one)."""
        xmin, _, _, ymax = self.bounds
        return Affine(self.cell_size_m, 0.0, xmin, 0.0, -self.cell_size_m, ymax)

    @property
    def n_cells(self) -> int:
        """Number of cells."""
        return self.shape[0] * self.shape[1]

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` in metres."""
        x0, y0 = self.origin_xy_m
        rows, cols = self.shape
        return (x0, y0, x0 + cols * self.cell_size_m, y0 + rows * self.cell_size_m)

    def check_same(self, other: Grid, what: str = "grid") -> None:
        """Raise :class:`GridMismatchError` unless ``other`` is this grid.

        ``what`` names the other grid's owner in the message.
        """
        if other != self:
            raise GridMismatchError(
                f"{what} is on {other!r}, expected {self!r} (shape, cell size and origin must match)"
            )

    # -------------------------------------------------------------- conversions
    def contains(self, x_m: Any, y_m: Any) -> np.ndarray | bool:
        """Whether world points lie inside the bounds (edges included; scalar or array)."""
        xmin, ymin, xmax, ymax = self.bounds
        x = np.asarray(x_m, dtype=float)
        y = np.asarray(y_m, dtype=float)
        inside = (x >= xmin) & (x <= xmax) & (y >= ymin) & (y <= ymax)
        return bool(inside) if inside.ndim == 0 else inside

    def rowcol(self, x_m: Any, y_m: Any) -> tuple[Any, Any]:
        """Cell ``(row, col)`` containing world points; points on the far edges map inside.

        Raises
        ------
        OutOfBoundsError
            If any point lies outside the bounds (or is NaN).
        """
        x, y = np.broadcast_arrays(np.asarray(x_m, dtype=float), np.asarray(y_m, dtype=float))
        inside = np.asarray(self.contains(x, y))
        if not np.all(inside):
            bad = np.flatnonzero(~inside.ravel())[0]
            px, py = x.ravel()[bad], y.ravel()[bad]
            box = ", ".join(fmt_number(float(b), 10) for b in self.bounds)
            raise OutOfBoundsError(f"point ({fmt_number(float(px), 10)}, {fmt_number(float(py), 10)}) m lies outside the "
                                   f"map bounds ({box})")
        x0, y0 = self.origin_xy_m
        col = np.minimum(((x - x0) / self.cell_size_m).astype(np.int64), self.shape[1] - 1)
        row = np.minimum(((y - y0) / self.cell_size_m).astype(np.int64), self.shape[0] - 1)
        if row.ndim == 0:
            return int(row), int(col)
        return row, col

    def xy(self, row: Any, col: Any) -> tuple[Any, Any]:
        """World coordinates (m) of cell centres (scalar or array)."""
        r, c = np.broadcast_arrays(np.asarray(row), np.asarray(col))
        x0, y0 = self.origin_xy_m
        x = x0 + (c + 0.5) * self.cell_size_m
        y = y0 + (r + 0.5) * self.cell_size_m
        if x.ndim == 0:
            return float(x), float(y)
        return x, y

    def cell_centres(self) -> tuple[np.ndarray, np.ndarray]:
        """1-D arrays of the x (per column) and y (per row) coordinates of cell centres."""
        x0, y0 = self.origin_xy_m
        d = self.cell_size_m
        return x0 + (np.arange(self.shape[1]) + 0.5) * d, y0 + (np.arange(self.shape[0]) + 0.5) * d

    def segment_cells(
        self, start_xy_m: tuple[float, float], end_xy_m: tuple[float, float]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cells crossed by a straight segment and the length of the segment in each.

        The traversal is exact: the segment is cut where it crosses grid lines, so the
        lengths sum to the segment's length.

        Returns
        -------
        rows, cols : ndarray of int
            Cells in the order they are crossed.
        lengths_m : ndarray of float
            Length of the segment inside each cell (m).

        Raises
        ------
        OutOfBoundsError
            If either end lies outside the grid.

        Examples
        --------
        >>> rows, cols, lengths = Grid((3, 3), 1.0).segment_cells((0.5, 0.5), (2.5, 1.5))
        >>> rows.tolist(), cols.tolist(), [round(float(v), 3) for v in lengths]
        ([0, 0, 1, 1], [0, 1, 1, 2], [0.559, 0.559, 0.559, 0.559])
        """
        (xa, ya), (xb, yb) = start_xy_m, end_xy_m
        self.rowcol(np.array([xa, xb]), np.array([ya, yb]))
        x0, y0 = self.origin_xy_m
        d = self.cell_size_m
        ua, va = (xa - x0) / d, (ya - y0) / d
        ub, vb = (xb - x0) / d, (yb - y0) / d
        ts = [np.array([0.0, 1.0])]
        for a, b in ((ua, ub), (va, vb)):
            if a != b:
                lo, hi = sorted((a, b))
                lines = np.arange(np.floor(lo) + 1, np.ceil(hi))
                ts.append((lines - a) / (b - a))
        t = np.unique(np.concatenate(ts))
        t = t[(t >= 0) & (t <= 1)]
        length = float(np.hypot(xb - xa, yb - ya))
        if length == 0.0:
            r, c = self.rowcol(xa, ya)
            return np.array([r]), np.array([c]), np.array([0.0])
        tm = 0.5 * (t[:-1] + t[1:])
        keep = np.diff(t) > 0
        tm = tm[keep]
        rows, cols = self.rowcol(xa + tm * (xb - xa), ya + tm * (yb - ya))
        lengths = np.diff(t)[keep] * length
        # Rounding can split a cell into a sliver and the rest (e.g. a crossing computed
        # just past the far map edge): merge consecutive pieces in the same cell.
        first = np.flatnonzero(np.concatenate(([True], (np.diff(rows) != 0) | (np.diff(cols) != 0))))
        return rows[first], cols[first], np.add.reduceat(lengths, first)
