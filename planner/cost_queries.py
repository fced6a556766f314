"""CostQueries: what an edge cost answers — segment, path and turn energies, free points, bounds, regions."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from terrawatt_base.errors import InvalidParameterError, OutOfBoundsError

from .kernels import walk_forward, walk_many
from .points import as_points

__all__ = ["CostQueries"]


class CostQueries:
    """The queries of :class:`~planner.EnergyCost` over its map, tables and packed arrays.

    A base class: :class:`~planner.EnergyCost` builds and validates the state these methods
    read (``terrain``, ``arrays``, ``blocked``, ``ground_rows``, ``turn_table_j``,
    ``min_energy_per_metre_j``, ``_components``).
    """

    @property
    def shape(self) -> tuple[int, int]:
        """Grid shape of the map."""
        return self.terrain.shape

    def check_inside(self, pts: np.ndarray, name: str) -> None:
        """Raise :class:`OutOfBoundsError` naming ``name`` if a point of ``pts`` (N, 2) lies outside the map."""
        inside = np.asarray(self.terrain.contains(pts[:, 0], pts[:, 1]))
        if not np.all(inside):
            bad = pts[~inside][0]
            raise OutOfBoundsError(
                f"{name} point {tuple(bad.tolist())!r} m lies outside the map bounds {self.terrain.bounds!r}"
            )

    def segment_energy_j(self, starts_xy_m: Any, ends_xy_m: Any) -> np.ndarray:
        """Energy (J) of driving each straight segment ``starts[i] -> ends[i]`` at the planning speed.

        Exact cell-by-cell integration; ``inf`` for a segment that crosses a blocked cell.

        Parameters
        ----------
        starts_xy_m, ends_xy_m : array_like, shape (N, 2) or (2,)
            Segment ends (m).

        Returns
        -------
        ndarray, shape (N,)

        Raises
        ------
        InvalidParameterError
            Wrong shapes or NaN/inf coordinates.
        OutOfBoundsError
            A point outside the map.
        """
        a = as_points(starts_xy_m, "starts_xy_m")
        b = as_points(ends_xy_m, "ends_xy_m")
        if a.shape != b.shape:
            raise InvalidParameterError(f"starts_xy_m {a.shape!r} and ends_xy_m {b.shape!r} must have equal shapes")
        self.check_inside(a, "starts_xy_m")
        self.check_inside(b, "ends_xy_m")
        arr = self.arrays
        return walk_many(
            arr.cells,
            arr.grade_table,
            arr.geo,
            np.array(a[:, 0]),  # fresh writable copies: one compiled signature for all callers
            np.array(a[:, 1]),
            np.array(b[:, 0]),
            np.array(b[:, 1]),
        )

    def segment_energy_one_j(self, xa: float, ya: float, xb: float, yb: float) -> float:
        """Energy (J) of one segment from scalars, without validation (compiled; for callbacks).

        Points outside the map, NaN, or a blocked crossing give ``inf``.
        """
        arr = self.arrays
        return walk_forward(arr.cells, arr.grade_table, arr.geo, xa, ya, xb, yb)

    def is_free(self, xy_m: Any) -> np.ndarray:
        """Whether points lie on free cells (inside the map, no obstacle, not too steep).

        Raises
        ------
        InvalidParameterError
            Wrong shape or NaN coordinates.
        OutOfBoundsError
            A point outside the map.
        """
        pts = as_points(xy_m, "xy_m")
        self.check_inside(pts, "xy_m")
        r, c = self.terrain.rowcol(pts[:, 0], pts[:, 1])
        return ~self.blocked[r, c]

    def turn_energies_j(self, waypoints_m: Any) -> tuple[np.ndarray, np.ndarray]:
        """Heading change (rad, in [0, pi]) and turn energy (J) at every waypoint of a polyline.

        The first and last waypoints have no turn. Zero-length segments (repeated points)
        have no heading: the turn is taken between the neighbouring non-degenerate segments,
        at the waypoint where the new heading starts.

        Returns
        -------
        angles_rad, energies_j : ndarray, shape (K,)
        """
        pts = as_points(waypoints_m, "waypoints_m")
        self.check_inside(pts, "waypoints_m")
        k = pts.shape[0]
        angles = np.zeros(k)
        if k < 3:
            return angles, np.zeros(k)
        seg = np.diff(pts, axis=0)
        nonzero = np.flatnonzero(np.hypot(seg[:, 0], seg[:, 1]) > 0)
        if nonzero.size >= 2:
            heading = np.arctan2(seg[nonzero, 1], seg[nonzero, 0])
            turn = np.abs((np.diff(heading) + math.pi) % (2 * math.pi) - math.pi)
            angles[nonzero[1:]] = turn  # waypoint index where segment nonzero[j] starts
        r, c = self.terrain.rowcol(pts[:, 0], pts[:, 1])
        rows = self.ground_rows[r, c]
        n_turn = self.turn_table_j.shape[1]
        f = angles / math.pi * (n_turn - 1)
        i0 = np.minimum(np.floor(f).astype(np.int64), n_turn - 2)
        w = f - i0
        energies = self.turn_table_j[rows, i0] * (1 - w) + self.turn_table_j[rows, i0 + 1] * w
        energies[angles == 0] = 0.0
        return angles, energies

    def path_energy_j(self, waypoints_m: Any) -> float:
        """Total energy (J) of a polyline: every segment plus the turns at its waypoints.

        ``inf`` when a segment crosses a blocked cell.

        Raises
        ------
        InvalidParameterError
            Fewer than 1 waypoint, wrong shape or NaN.
        OutOfBoundsError
            A waypoint outside the map.
        """
        pts = as_points(waypoints_m, "waypoints_m")
        if pts.shape[0] < 2:
            return 0.0
        seg = self.segment_energy_j(pts[:-1], pts[1:])
        _, turns = self.turn_energies_j(pts)
        return float(seg.sum() + turns.sum())

    def surface_length_m(self, waypoints_m: Any) -> float:
        """Length (m) of a polyline along the terrain surface: per cell, horizontal length
        times ``sqrt(1 + grade**2)`` with the cell's grade in the direction of travel.

        Raises
        ------
        InvalidParameterError, OutOfBoundsError
            Bad shape / NaN, or a waypoint outside the map.
        """
        pts = as_points(waypoints_m, "waypoints_m")
        self.check_inside(pts, "waypoints_m")
        gx, gy = self.terrain["grad_x"], self.terrain["grad_y"]
        total = 0.0
        for a, b in zip(pts[:-1], pts[1:]):
            length = math.hypot(b[0] - a[0], b[1] - a[1])
            if length == 0.0:
                continue
            rows, cols, pieces = self.terrain.segment_cells(tuple(a), tuple(b))
            grade = (gx[rows, cols] * (b[0] - a[0]) + gy[rows, cols] * (b[1] - a[1])) / length
            total += float(np.sum(pieces * np.sqrt(1.0 + grade**2)))
        return total

    def lower_bound_j(self, a_xy_m: Any, b_xy_m: Any) -> np.ndarray:
        """Admissible lower bound (J) on the drive energy of any route from ``a`` to ``b``.

        ``min_energy_per_metre_j * |b - a|``: every route of length ``L >= |b - a|`` only
        crosses free cells, and on each of them a straight piece costs at least the lowest
        energy per metre at any grade that cell can present (``|grade| <= tan(slope)``).
        It never overestimates (the elevation change is deliberately not used: with
        per-cell gradients the integrated grade along a route is not exactly
        ``z(b) - z(a)``, so a grade term could overestimate).

        Returns
        -------
        ndarray, shape (N,)
        """
        a = as_points(a_xy_m, "a_xy_m")
        b = as_points(b_xy_m, "b_xy_m")
        return self.min_energy_per_metre_j * np.hypot(b[:, 0] - a[:, 0], b[:, 1] - a[:, 1])

    def components(self) -> np.ndarray:
        """Label of the 4-connected region of free cells holding each cell (``0`` = blocked).

        Two points are joined by some valid polyline exactly when their cells share a label
        (a valid segment crosses a chain of edge-adjacent free cells, and a corner crossing
        needs both side cells free).
        """
        if self._components is None:
            from scipy import ndimage

            labels, _ = ndimage.label(~self.blocked)
            self._components = labels
        return self._components
