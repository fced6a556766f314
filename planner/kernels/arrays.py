"""CostArrays: the packed, read-only per-cell arrays that the compiled kernels walk over."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from terrain.grid import Grid

__all__ = [
    "CostArrays",
    "GEO_X0",
    "GEO_Y0",
    "GEO_CELL",
    "GEO_NROWS",
    "GEO_NCOLS",
    "GEO_GRADE_MIN",
    "GEO_INV_DGRADE",
]

# Layout of the float64 ``geo`` vector handed to the kernels.
GEO_X0, GEO_Y0, GEO_CELL, GEO_NROWS, GEO_NCOLS, GEO_GRADE_MIN, GEO_INV_DGRADE = range(7)


@dataclass(frozen=True, eq=False)
class CostArrays:
    """The arrays of an :class:`~planner.EnergyCost` in the layout the kernels read (all read-only).

    Attributes
    ----------
    grid : terrain.grid.Grid
        The map's grid.
    cells : ndarray, shape (rows, cols, 3)
        Per cell: ``grad_x``, ``grad_y`` (elevation gradients) and the table row serving the
        cell as a float (``-1``: blocked).
    grade_table : ndarray, shape (n_rows, n_grade)
        Energy per horizontal metre (J/m) at grades uniformly spaced over
        ``[-grade_max, grade_max]``; ``inf`` = undrivable in that direction.
    turn_table : ndarray, shape (n_rows, n_turn)
        Turn-in-place energy (J) at angles uniformly spaced over ``[0, pi]``.
    geo : ndarray, shape (7,)
        ``x0, y0, cell size, rows, cols, -grade_max, 1 / grade step`` (indices ``GEO_*``).
    """

    grid: Grid
    cells: np.ndarray
    grade_table: np.ndarray
    turn_table: np.ndarray
    geo: np.ndarray

    def __post_init__(self) -> None:
        for arr in (self.cells, self.grade_table, self.turn_table, self.geo):
            arr.setflags(write=False)

    @classmethod
    def build(
        cls,
        grid: Grid,
        grad_x: np.ndarray,
        grad_y: np.ndarray,
        table_rows: np.ndarray,
        blocked: np.ndarray,
        grade_table: np.ndarray,
        turn_table: np.ndarray,
        grade_max: float,
    ) -> CostArrays:
        """Pack validated layers and tables (the caller owns validation)."""
        cells = np.empty(tuple(grid.shape) + (3,), dtype=np.float64)
        cells[..., 0] = grad_x
        cells[..., 1] = grad_y
        cells[..., 2] = np.where(blocked, -1.0, table_rows)
        dg = 2.0 * grade_max / (grade_table.shape[1] - 1)
        x0, y0 = grid.origin_xy_m
        rows, cols = grid.shape
        geo = np.array([x0, y0, grid.cell_size_m, rows, cols, -grade_max, 1.0 / dg], dtype=np.float64)
        return cls(grid, cells, grade_table, turn_table, geo)

    def with_tables(
        self, table_rows: np.ndarray, blocked: np.ndarray, grade_table: np.ndarray, turn_table: np.ndarray
    ) -> CostArrays:
        """The same geometry (gradients, grade grid) with new tables and table rows."""
        cells = self.cells.copy()
        cells[..., 2] = np.where(blocked, -1.0, table_rows)
        return CostArrays(self.grid, cells, grade_table, turn_table, self.geo)

    @property
    def grade_step(self) -> float:
        """Spacing of the grade grid of :attr:`grade_table`."""
        return 2.0 * self.grade_max / (self.grade_table.shape[1] - 1)

    @property
    def grade_max(self) -> float:
        """Largest grade of the grade grid (``tan`` of the slope limit)."""
        return -float(self.geo[GEO_GRADE_MIN])

    def same_geometry(self, other: CostArrays) -> bool:
        """Whether ``other`` has this grid and grade grid (its lattice weights are comparable)."""
        return bool(np.array_equal(self.geo, other.geo))
