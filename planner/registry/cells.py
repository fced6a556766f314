"""Cell selections of the registry's grid: masks, (rows, cols) pairs and regions as flat indices."""

from __future__ import annotations

from typing import Any

import numpy as np

from terrawatt_base.errors import GridMismatchError, InvalidParameterError, OutOfBoundsError

from .records import Cells, FlaggedRegion

__all__ = ["check_rows_cols", "flat_cells", "unflat"]


def check_rows_cols(shape: tuple[int, int], rows: Any, cols: Any) -> tuple[np.ndarray, np.ndarray]:
    """``rows`` and ``cols`` as equal-length 1-D ``int64`` arrays of cells inside ``shape``.

    Raises
    ------
    InvalidParameterError
        Arrays that are not 1-D, not integer, or of different lengths.
    OutOfBoundsError
        A cell outside the grid (the message names the first one).
    """
    r = np.atleast_1d(np.asarray(rows))
    c = np.atleast_1d(np.asarray(cols))
    for name, arr in (("rows", r), ("cols", c)):
        if arr.ndim != 1:
            raise InvalidParameterError(f"{name} must be 1-D, got shape {arr.shape!r}")
        if arr.size and (arr.dtype == bool or not np.issubdtype(arr.dtype, np.integer)):
            raise InvalidParameterError(f"{name} must hold integer cell indices, got dtype {arr.dtype}")
    if r.shape != c.shape:
        raise InvalidParameterError(f"rows and cols must have the same length, got {r.size} and {c.size}")
    r = r.astype(np.int64)
    c = c.astype(np.int64)
    bad = (r < 0) | (r >= shape[0]) | (c < 0) | (c >= shape[1])
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise OutOfBoundsError(
            f"cell (row={int(r[i])!r}, col={int(c[i])!r}) at index {i} lies outside the grid {shape!r}"
        )
    return r, c


def flat_cells(shape: tuple[int, int], cells: Cells, what: str = "cells") -> np.ndarray:
    """Sorted unique flat indices of ``cells`` (a mask, a (rows, cols) tuple or a FlaggedRegion).

    ``what`` names the argument in messages.

    Raises
    ------
    InvalidParameterError
        A mask that is not boolean, a tuple that is not (rows, cols), bad index arrays.
    GridMismatchError
        A mask of another shape.
    OutOfBoundsError
        Cells outside the grid.
    """
    if isinstance(cells, FlaggedRegion):
        r, c = check_rows_cols(shape, cells.rows, cells.cols)
    elif isinstance(cells, tuple):
        if len(cells) != 2:
            raise InvalidParameterError(f"{what} as a tuple must be (rows, cols), got {len(cells)} items")
        r, c = check_rows_cols(shape, *cells)
    else:
        mask = np.asarray(cells)
        if mask.dtype != bool:
            raise InvalidParameterError(
                f"{what} must be a boolean mask, a (rows, cols) tuple or a FlaggedRegion, got an "
                f"array of dtype {mask.dtype}"
            )
        if mask.shape != tuple(shape):
            raise GridMismatchError(f"{what} mask has shape {mask.shape!r}; this registry's grid is {shape!r}")
        return np.flatnonzero(mask)
    return np.unique(r * shape[1] + c)


def unflat(shape: tuple[int, int], flat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(rows, cols)`` (``int64``) of flat cell indices on a grid of ``shape``."""
    rows, cols = np.divmod(np.asarray(flat).astype(np.int64), shape[1])
    return rows, cols
