"""Observed-vs-predicted charge per cell, the relative error, flags with hysteresis, flagged regions."""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from scipy import ndimage

from terrain.grid import Grid
from terrawatt_base.checks import readonly
from terrawatt_base.errors import DataError, InvalidParameterError

from .assignment import CellAssignment
from .cells import check_rows_cols, flat_cells, unflat
from .records import Cells, FlaggedRegion, UpdatePolicy

__all__ = ["CellEvidence", "relative_error"]


def relative_error(predicted: Any, measured: Any, count: Any) -> np.ndarray:
    """``(predicted - measured) / |measured|`` elementwise; NaN where ``count`` is 0.

    Where the measured charge is exactly 0 the error is 0 if the predicted one is 0 too,
    else ``±inf``.

    Examples
    --------
    >>> relative_error([1.2, 0.0, 1.0, 5.0], [1.0, 0.0, 0.0, 2.0], [3, 1, 1, 0]).tolist()
    [0.19999999999999996, 0.0, inf, nan]
    """
    predicted = np.asarray(predicted, dtype=np.float64)
    measured = np.asarray(measured, dtype=np.float64)
    diff = predicted - measured
    denom = np.abs(measured)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(denom > 0, diff / np.where(denom > 0, denom, 1.0), np.sign(diff) * np.inf)
    out = np.where((denom == 0) & (diff == 0), 0.0, out)
    return np.where(np.asarray(count) > 0, out, np.nan)


def _current_array(name: str, value: Any, n: int) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{name} must be an array of numbers: {exc}") from exc
    if arr.ndim not in (1, 2) or arr.shape[0] != n:
        raise InvalidParameterError(f"{name} must have shape ({n},) or ({n}, k) to match rows/cols, got {arr.shape!r}")
    finite = np.isfinite(arr)
    if not np.all(finite):
        bad = np.flatnonzero(~finite.reshape(n, -1).all(axis=1))
        raise DataError(
            f"{name} holds NaN/inf in {bad.size} sample(s), first at index {int(bad[0])}; "
            "expected finite currents (repair or drop them before recording)"
        )
    return arr if arr.ndim == 1 else arr.sum(axis=1)


class CellEvidence:
    """Measured and predicted charge (C), sample count and flag state of every cell of a grid.

    A registry's :attr:`~planner.registry.CellModelRegistry.evidence`: what was recorded
    where, how wrong the serving model is there, and which cells need new data. Cells are
    given as ``rows, cols`` arrays or a selection (a mask of the grid's shape, a ``(rows,
    cols)`` tuple or a :class:`FlaggedRegion`), checked against the grid.

    Parameters
    ----------
    shape : (int, int)
        ``(rows, cols)`` of the grid.
    grid : Grid, optional
        The grid's cell size and origin: regions then carry world coordinates.
    assignment : CellAssignment, optional
        Which model serves each cell (each region's ``model_ids``); without it every cell
        is on the prior.

    Examples
    --------
    >>> ev = CellEvidence((2, 2))
    >>> ev.record([1, 1], [1, 1], [2.0, 2.0], [1.0, 1.0], 0.5)
    >>> ev.measured_charge_c.tolist(), ev.relative_error()[1, 1].item()
    ([[0.0, 0.0], [0.0, 2.0]], -0.5)
    """

    def __init__(self, shape: tuple[int, int], *, grid: Grid | None = None,
                 assignment: CellAssignment | None = None) -> None:
        self._shape = (int(shape[0]), int(shape[1]))
        self._grid = grid
        self._assignment = assignment
        self._measured_c = np.zeros(self._shape, np.float64)
        self._predicted_c = np.zeros(self._shape, np.float64)
        self._count = np.zeros(self._shape, np.int64)
        self._flag = np.zeros(self._shape, bool)

    # ----------------------------------------------------------------- state
    @property
    def measured_charge_c(self) -> np.ndarray:
        """Measured charge (C) per cell (read-only copy)."""
        return readonly(self._measured_c)

    @property
    def predicted_charge_c(self) -> np.ndarray:
        """Predicted charge (C) per cell (read-only copy)."""
        return readonly(self._predicted_c)

    @property
    def sample_count(self) -> np.ndarray:
        """Samples recorded per cell since its evidence was last cleared (read-only copy)."""
        return readonly(self._count)

    @property
    def flag_state(self) -> np.ndarray:
        """The flags as of the last :meth:`flagged` call (read-only copy)."""
        return readonly(self._flag)

    @property
    def cells_with_evidence(self) -> int:
        """Number of cells with at least one sample."""
        return int(np.count_nonzero(self._count))

    def restore(self, measured_c: np.ndarray, predicted_c: np.ndarray, count: np.ndarray, flag: np.ndarray) -> None:
        """Set the state read from a saved registry (the store has checked shapes and values)."""
        self._measured_c[...] = measured_c
        self._predicted_c[...] = predicted_c
        self._count[...] = count
        self._flag[...] = flag

    # ---------------------------------------------------------------- update
    def record(self, rows: Any, cols: Any, measured_current_a: Any, predicted_current_a: Any, dt_s: Any) -> None:
        """Accumulate measured and predicted charge per cell from driving samples.

        Each sample ``i`` adds ``measured_current_a[i] * dt_s[i]`` to the measured charge
        (C) of cell ``(rows[i], cols[i])``, ``predicted_current_a[i] * dt_s[i]`` to its
        predicted charge and 1 to its sample count. Vectorised (``np.add.at``); nothing is
        recorded if any input is bad.

        Parameters
        ----------
        rows, cols : array_like of int, shape (N,)
            Cell of each sample (e.g. from :meth:`TerrainMap.rowcol` of the robot's position).
        measured_current_a, predicted_current_a : array_like of float, shape (N,) or (N, k)
            Drive current (A); a 2-D array is summed over its ``k`` channels (e.g. left and
            right motors). Pass the quantity to compare, e.g. absolute currents.
        dt_s : float or array_like of float, shape (N,)
            Duration each sample stands for (s, > 0).

        Raises
        ------
        InvalidParameterError
            Arrays whose lengths differ, non-integer cells, arrays of the wrong rank.
        OutOfBoundsError
            Cells outside the grid.
        DataError
            NaN/inf currents or durations, non-positive durations.
        """
        r, c = check_rows_cols(self._shape, rows, cols)
        flat = r * self._shape[1] + c
        n = flat.size
        meas = _current_array("measured_current_a", measured_current_a, n)
        pred = _current_array("predicted_current_a", predicted_current_a, n)
        dt = np.asarray(dt_s, dtype=np.float64)
        if dt.ndim > 1 or (dt.ndim == 1 and dt.size != n):
            raise InvalidParameterError(
                f"dt_s must be a scalar or have one value per sample ({n}), got shape {dt.shape!r}"
            )
        if not np.all(np.isfinite(dt)) or np.any(dt <= 0):
            bad = np.flatnonzero(~(np.isfinite(np.atleast_1d(dt)) & (np.atleast_1d(dt) > 0)))
            raise DataError(
                f"dt_s must be finite and > 0; {bad.size} value(s) are not, first "
                f"{np.atleast_1d(dt)[bad[0]]!r} at index {int(bad[0])}"
            )
        if n == 0:
            return
        np.add.at(self._measured_c.reshape(-1), flat, meas * dt)
        np.add.at(self._predicted_c.reshape(-1), flat, pred * dt)
        np.add.at(self._count.reshape(-1), flat, 1)

    def reset(self, cells: Cells | None = None) -> None:
        """Forget the evidence (charges, counts) and flag state of ``cells`` (all when ``None``).

        Call it after data were collected and a model updated by other means than the
        registry's :meth:`~planner.registry.CellModelRegistry.propose_update` /
        :meth:`~planner.registry.CellModelRegistry.assign` (which reset the cells they change).

        Raises
        ------
        InvalidParameterError, GridMismatchError, OutOfBoundsError
            Bad ``cells``.
        """
        self.clear(np.arange(self._shape[0] * self._shape[1]) if cells is None else flat_cells(self._shape, cells))

    def clear(self, flat: np.ndarray) -> None:
        """Forget charges, counts and flags of the cells of flat indices ``flat`` (checked by the caller)."""
        self._measured_c.reshape(-1)[flat] = 0.0
        self._predicted_c.reshape(-1)[flat] = 0.0
        self._count.reshape(-1)[flat] = 0
        self._flag.reshape(-1)[flat] = False

    # ---------------------------------------------------------------- errors
    def relative_error(self) -> np.ndarray:
        """Relative error of integrated current per cell, ``(predicted - measured) / |measured|``.

        Positive when the model over-predicts. ``NaN`` where the cell has no samples; where
        the measured charge is exactly 0 it is 0 if the predicted charge is 0 too, else
        ``±inf`` (:func:`relative_error`).

        Returns
        -------
        numpy.ndarray of float64, shape of the grid
        """
        return relative_error(self._predicted_c, self._measured_c, self._count)

    def relative_error_over(self, cells: Cells) -> float:
        """Relative error of the charge integrated over a set of cells (NaN without samples).

        Raises
        ------
        InvalidParameterError, GridMismatchError, OutOfBoundsError
            Bad ``cells``.
        """
        flat = flat_cells(self._shape, cells)
        p = float(self._predicted_c.reshape(-1)[flat].sum())
        m = float(self._measured_c.reshape(-1)[flat].sum())
        n = int(self._count.reshape(-1)[flat].sum())
        return float(relative_error(np.array(p), np.array(m), np.array(n)))

    def flagged(self, policy: UpdatePolicy) -> np.ndarray:
        """Cells whose model needs new data under ``policy``, with hysteresis.

        A cell becomes flagged when it has at least ``policy.min_samples`` samples and
        ``|relative error| > threshold_pct``; a flagged cell stays flagged until its error
        falls below ``threshold_pct - hysteresis_pct``. The state is kept between calls, so
        each call advances it (and :meth:`reset` clears it).

        Returns
        -------
        numpy.ndarray of bool, shape of the grid (a copy)

        Raises
        ------
        InvalidParameterError
            ``policy`` is not an :class:`UpdatePolicy`.
        """
        if not isinstance(policy, UpdatePolicy):
            raise InvalidParameterError(f"policy must be an UpdatePolicy, got {type(policy).__name__}")
        with np.errstate(invalid="ignore"):
            err_pct = 100.0 * np.abs(self.relative_error())
            enough = self._count >= policy.min_samples
            above = enough & (err_pct > policy.threshold_pct)
            cleared = err_pct < policy.clear_below_pct
        self._flag = above | (self._flag & ~cleared)
        return self._flag.copy()

    def flagged_regions(self, policy: UpdatePolicy, *, connectivity: Literal[4, 8] = 8) -> list[FlaggedRegion]:
        """Connected regions of flagged cells (advances the flag state like :meth:`flagged`).

        Parameters
        ----------
        policy : UpdatePolicy
            Regions with fewer than ``policy.min_region_cells`` cells are left out.
        connectivity : {4, 8}
            Cells touching by an edge (4) or also by a corner (8) belong to one region.

        Returns
        -------
        list of FlaggedRegion
            In label order (raster scan order of each region's first cell); with world
            coordinates when the evidence has a grid, with the models serving each region.

        Raises
        ------
        InvalidParameterError
            Bad policy or connectivity.
        """
        if connectivity not in (4, 8):
            raise InvalidParameterError(f"connectivity must be 4 or 8, got {connectivity!r}")
        mask = self.flagged(policy)
        structure = ndimage.generate_binary_structure(2, 1 if connectivity == 4 else 2)
        labels, n_regions = ndimage.label(mask, structure=structure)
        if n_regions == 0:
            return []
        flat_labels = labels.reshape(-1)
        members = np.flatnonzero(flat_labels)  # sorted flat indices
        members = members[np.argsort(flat_labels[members], kind="stable")]  # grouped by label
        seg = flat_labels[members] - 1  # region index of each member, 0-based
        sizes = np.bincount(seg, minlength=n_regions)
        starts = np.concatenate(([0], np.cumsum(sizes)))
        rows, cols = unflat(self._shape, members)
        # per-region statistics in one pass (no Python loop over cells)
        heads = starts[:-1]
        row_min, row_max = np.minimum.reduceat(rows, heads), np.maximum.reduceat(rows, heads)
        col_min, col_max = np.minimum.reduceat(cols, heads), np.maximum.reduceat(cols, heads)
        centre_r = np.add.reduceat(rows, heads) / sizes
        centre_c = np.add.reduceat(cols, heads) / sizes
        dist2 = (rows - centre_r[seg]) ** 2 + (cols - centre_c[seg]) ** 2
        rep_idx = np.lexsort((dist2, seg))[heads]  # nearest member; ties -> lowest flat index
        pred_sum = np.add.reduceat(self._predicted_c.reshape(-1)[members], heads)
        meas_sum = np.add.reduceat(self._measured_c.reshape(-1)[members], heads)
        n_sum = np.add.reduceat(self._count.reshape(-1)[members], heads)
        errors = relative_error(pred_sum, meas_sum, n_sum)
        cell_model = (np.zeros(self._shape, np.int64) if self._assignment is None
                      else np.asarray(self._assignment.cell_model, np.int64))
        n_models = int(cell_model.max()) + 1  # any bound above every id decodes the pairs alike
        pairs = np.unique(seg * n_models + cell_model.reshape(-1)[members])
        pair_seg, pair_model = np.divmod(pairs, n_models)
        pair_starts = np.searchsorted(pair_seg, np.arange(n_regions + 1))
        regions: list[FlaggedRegion] = []
        for k in np.flatnonzero(sizes >= policy.min_region_cells):
            sl = slice(starts[k], starts[k + 1])
            rep = (int(rows[rep_idx[k]]), int(cols[rep_idx[k]]))
            bbox = (int(row_min[k]), int(col_min[k]), int(row_max[k]), int(col_max[k]))
            rep_xy: tuple[float, float] | None = None
            bounds: tuple[float, float, float, float] | None = None
            if self._grid is not None:
                grid = self._grid
                d = grid.cell_size_m
                x0, y0 = grid.origin_xy_m
                rep_xy = grid.xy(rep[0], rep[1])
                bounds = (x0 + bbox[1] * d, y0 + bbox[0] * d, x0 + (bbox[3] + 1) * d, y0 + (bbox[2] + 1) * d)
            regions.append(
                FlaggedRegion(
                    region_id=int(k) + 1,
                    rows=readonly(rows[sl]),
                    cols=readonly(cols[sl]),
                    cell_count=int(sizes[k]),
                    bbox_rows_cols=bbox,
                    representative_row_col=rep,
                    representative_xy_m=rep_xy,
                    bounds_m=bounds,
                    relative_error=float(errors[k]),
                    sample_count=int(n_sum[k]),
                    model_ids=tuple(pair_model[pair_starts[k]:pair_starts[k + 1]].tolist()),
                )
            )
        return regions
