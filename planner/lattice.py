"""Reference lattice planner: a directed 16-connected grid graph, solved exactly (A* or scipy's Dijkstra).

Nodes sit at cell centres (every ``stride_cells``-th cell in each direction). Each node has
16 out-edges: the 8 king moves and the 8 knight moves of the node grid. The weight of an
edge is :meth:`EnergyCost.segment_energy_j` of the straight segment between the two node
centres (directed: uphill ``!=`` downhill); edges that cross a blocked cell, or meet a
grade their ground cannot be driven at in that direction, are absent.
Both directions of a pair are costed in one cell walk by the compiled kernels of
:mod:`planner.kernels` (in parallel on large lattices).

A query joins the start and goal points to the lattice nodes within ``1.5 * stride`` cells
(plus the direct start-goal segment), so a lattice route is ``start, node, ..., node, goal``.
This lattice's optimum is the minimum *drive* energy over such routes: a heading-free graph
cannot see turns, which every route evaluation prices. The planner searches the same moves
over (node, heading) instead (:mod:`planner.heading_lattice`), whose optimum pays for its
turns; this lattice's weights are its arcs' drive part. Collinear runs of moves are merged
into single segments (same energy).

A second graph with the same edges weighted by their length gives the shortest-distance
route, straightened afterwards by pulling the string (greedy line-of-sight shortcuts).

A lattice refreshed for new energy tables (:meth:`Lattice.refreshed`) records which moves
changed energy (:attr:`Lattice.changed_moves`, ids ``node * 16 + k`` with ``k`` indexing
:data:`LATTICE_OFFSETS`), so an incremental search (:class:`planner.replan.IncrementalPlanner`)
repairs only what they touch.

:meth:`Lattice.shortest_path` is a compiled A* that stops once no open node can beat the best
route found, with the heuristic ``min_energy_per_metre_j * |node - goal|`` (energy) or
``|node - goal|`` (length) — a lower bound of any route's rest, and consistent, since every
move costs at least that per metre of its length. :meth:`Lattice.paths_from` labels the whole
graph from one start with :func:`scipy.sparse.csgraph.dijkstra` (one search for many goals).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from terrawatt_base.checks import check_int
from terrawatt_base.errors import InvalidParameterError, UnknownNameError

from .edge_cost import EnergyCost
from .kernels import UNIT_HALF, astar, lattice_reweight, lattice_weights
from .kernels.graph import reweight_band
from .points import as_points

__all__ = ["Lattice", "LatticePath", "LATTICE_OFFSETS", "LATTICE_WEIGHTS"]

#: All 16 (row, col) node offsets: the 8 half-plane moves (:data:`~planner.kernels.UNIT_HALF`) and their
#: negatives, ``LATTICE_OFFSETS[k + 8] == -LATTICE_OFFSETS[k]``.
LATTICE_OFFSETS = np.concatenate([UNIT_HALF, -UNIT_HALF])
#: Edge weights a lattice can search with.
LATTICE_WEIGHTS = ("energy", "length")


@dataclass(frozen=True)
class LatticePath:
    """A lattice query's answer.

    Attributes
    ----------
    found : bool
        Whether the lattice joins start and goal.
    waypoints_m : ndarray, shape (K, 2)
        ``start, ..., goal`` with collinear runs merged; empty (0, 2) when not found.
    objective : float
        Sum of the searched edge weights (drive energy in J, or length in m); ``inf`` when
        not found.
    weight : str
        ``"energy"`` or ``"length"``.
    solve_time_s : float
        Seconds spent in the query (graph building excluded).
    """

    found: bool
    waypoints_m: np.ndarray
    objective: float
    weight: str
    solve_time_s: float

    def __post_init__(self) -> None:
        if self.weight not in LATTICE_WEIGHTS:
            raise UnknownNameError(f"weight must be one of {LATTICE_WEIGHTS!r}, got {self.weight!r}")
        wp = np.asarray(self.waypoints_m, dtype=float)
        if wp.ndim != 2 or wp.shape[1] != 2:
            raise InvalidParameterError(f"waypoints_m must have shape (K, 2), got {wp.shape!r}")
        if self.found != (wp.shape[0] >= 2):
            raise InvalidParameterError(f"found={self.found!r} but waypoints_m has {wp.shape[0]} points")
        wp.setflags(write=False)
        object.__setattr__(self, "waypoints_m", wp)


class Lattice:
    """Directed 16-connected lattice over an :class:`EnergyCost`'s map.

    Build it once per cost (the graph is the expensive part; :meth:`for_cost` caches it on
    the cost object) and query it for any start and goal.

    Parameters
    ----------
    cost : EnergyCost
        Edge costs and blocked cells.
    stride_cells : int
        Node spacing in cells (1 = a node at every cell centre).

    Attributes
    ----------
    node_rows, node_cols : ndarray of int
        Map rows / columns of the node grid.
    build_time_s : float
        Seconds spent building both graphs.
    n_edges : int
        Number of directed edges.
    changed_moves : ndarray of int64 or None
        For a lattice made by :meth:`refreshed`: the ids ``node * 16 + k`` (``k`` indexing
        :data:`LATTICE_OFFSETS`) of the moves whose energy differs from the lattice it was
        refreshed from (a move appearing or vanishing included), ascending; ``None`` for a
        lattice built from scratch.

    Raises
    ------
    InvalidParameterError
        ``stride_cells`` not a positive integer, or a map too small for it.

    Examples
    --------
    >>> from planner import CostSpec
    >>> from terrain import flat_map
    >>> tmap = flat_map((30, 40), 1.0)  # level asphalt, 1 m cells
    >>> cost = CostSpec(speed_mps=0.5).build(tmap)  # the Husky's physics on the asphalt preset
    >>> lat = Lattice(cost, stride_cells=1)
    >>> path = lat.shortest_path((1.0, 1.0), (30.0, 20.0))
    >>> path.waypoints_m.shape  # string-pulled: level ground needs no intermediate waypoint
    (2, 2)
    """

    def __init__(self, cost: EnergyCost, stride_cells: int = 1) -> None:
        if not isinstance(cost, EnergyCost):
            raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
        s = check_int("stride_cells", stride_cells, low=1)
        t0 = time.perf_counter()
        rows, cols = cost.shape
        off = s // 2
        self.cost = cost
        self.stride_cells = s
        self.node_rows = np.arange(off, rows, s)
        self.node_cols = np.arange(off, cols, s)
        ni, nj = self.node_rows.size, self.node_cols.size
        if ni < 2 or nj < 2:
            raise InvalidParameterError(
                f"stride_cells={stride_cells!r} leaves a {ni} x {nj} node grid on a {rows} x {cols} map; need >= 2 x 2"
            )
        self._ni, self._nj = ni, nj
        self._offset = off
        arr = cost.arrays
        w = lattice_weights(arr.cells, arr.grade_table, arr.geo, s, off, ni, nj, UNIT_HALF)
        self._set_structure(w)
        xc, yc = cost.terrain.cell_centres()
        self._node_x = xc[self.node_cols]
        self._node_y = yc[self.node_rows]
        #: Directed moves whose energy was computed when this lattice was made (2 per walk).
        self.edges_computed = int(w.size - np.count_nonzero(self._out_of_grid_mask()))
        self.changed_moves: np.ndarray | None = None
        self._token = object()  # identifies this version of the weights (see changed_moves_since)
        self._refreshed_from: object | None = None
        self.build_time_s = time.perf_counter() - t0

    def _out_of_grid_mask(self) -> np.ndarray:
        """(n_nodes, 16) mask of moves that leave the node grid."""
        i = np.arange(self._ni)[:, None, None] + LATTICE_OFFSETS[None, None, :, 0]
        j = np.arange(self._nj)[None, :, None] + LATTICE_OFFSETS[None, None, :, 1]
        return ((i < 0) | (i >= self._ni) | (j < 0) | (j >= self._nj)).reshape(self.n_nodes, -1)

    def _set_structure(self, w: np.ndarray) -> None:
        """CSR graphs (energy and length weights) from the dense (n_nodes, 16) energies ``w``."""
        ni, nj, s = self._ni, self._nj, self.stride_cells
        mask = np.isfinite(w)
        delta = LATTICE_OFFSETS[:, 0] * nj + LATTICE_OFFSETS[:, 1]
        n = ni * nj
        targets = (np.arange(n, dtype=np.int64)[:, None] + delta[None, :])[mask].astype(np.int32)
        indptr = np.zeros(n + 1, dtype=np.int32)
        np.cumsum(mask.sum(axis=1), out=indptr[1:])
        pos = np.full(w.shape, -1, dtype=np.int32)
        pos[mask] = np.arange(targets.size, dtype=np.int32)
        self._pos = pos
        self._indices = targets
        self._indptr = indptr
        step_m = np.hypot(LATTICE_OFFSETS[:, 0], LATTICE_OFFSETS[:, 1]) * s * self.cost.terrain.cell_size_m
        self._energy: np.ndarray | tuple = w[mask]  # or (base, patches): see _energy_data
        self._length = np.broadcast_to(step_m, w.shape)[mask]
        self.n_edges = int(targets.size)

    def _energy_data(self) -> np.ndarray:
        """The energy weights, made whole on first use after a refresh.

        A refreshed lattice holds its weights as ``(base, patches)``: its ancestor's array and
        the slices ``(lo, values)`` recomputed since, applied in order (a refresh copies only
        the slice of edges it may change, not every weight). The attribute is read and
        replaced whole, so concurrent readers at worst both build the array.
        """
        e = self._energy
        if isinstance(e, tuple):
            base, patches = e
            e = base.copy()
            for lo, values in patches:
                e[lo:lo + values.size] = values
            self._energy = e
        return e

    def _energy_slice(self, lo: int, hi: int) -> np.ndarray:
        """A copy of the energy weights ``[lo, hi)`` (without making the whole array)."""
        e = self._energy
        if not isinstance(e, tuple):
            return e[lo:hi].copy()
        base, patches = e
        out = base[lo:hi].copy()
        for plo, values in patches:
            a, b = max(lo, plo), min(hi, plo + values.size)
            if a < b:
                out[a - lo:b - lo] = values[a - plo:b - plo]
        return out

    def _weights(self, weight: str) -> np.ndarray:
        return self._energy_data() if weight == "energy" else self._length

    def refreshed(self, cost: EnergyCost, changed_cells: np.ndarray) -> Lattice:
        """This lattice over ``cost`` (same geometry, new tables), recomputing only changed edges.

        An edge's energy depends only on the table rows of the cells its segment crosses, all
        inside the box of cells spanned by its two nodes; the edges whose box holds a cell of
        ``changed_cells`` are recomputed (both directions in one walk, in parallel), the other
        weights and the graph structure are shared. If an edge would appear or vanish (a
        grade becoming drivable or undrivable) the structure is rebuilt from all weights.
        The result's weights equal those of ``Lattice(cost, stride_cells)`` exactly.

        Only the slice of edge weights the recomputed moves can fall in is copied: the new
        lattice reads the others from this one's array, and makes its whole array on its first
        search, :meth:`graph`, or :meth:`move_energies_j` of every move (this lattice is never
        changed). :attr:`changed_moves` lists the moves whose energy changed.

        Parameters
        ----------
        cost : EnergyCost
            A cost made by :meth:`EnergyCost.with_tables` from this lattice's cost (same
            map, blocked cells and grade grid).
        changed_cells : ndarray of bool, shape (rows, cols)
            Cells whose table row content changed.

        Returns
        -------
        Lattice
            A new lattice; ``edges_computed`` counts the directed moves recomputed,
            ``changed_moves`` lists the moves whose energy changed and ``build_time_s`` the
            seconds spent.

        Raises
        ------
        InvalidParameterError
            ``cost`` on another grid or with other blocked cells; a mask of the wrong shape.
        """
        t0 = time.perf_counter()
        if not isinstance(cost, EnergyCost):
            raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
        old = self.cost
        if (cost.terrain is not old.terrain and not cost.terrain.same_grid(old.terrain)) or not np.array_equal(
            cost.blocked, old.blocked
        ) or not cost.arrays.same_geometry(old.arrays):
            raise InvalidParameterError(
                "cost must share this lattice's map geometry (grid, blocked cells, grade grid); build a new Lattice"
            )
        changed = np.asarray(changed_cells, dtype=bool)
        if changed.shape != cost.shape:
            raise InvalidParameterError(f"changed_cells must have shape {cost.shape!r}, got {changed.shape!r}")
        new = object.__new__(Lattice)
        new.__dict__.update(self.__dict__)
        new.cost = cost
        new._token, new._refreshed_from = object(), self._token
        if not changed.any():
            new.edges_computed = 0
            new.changed_moves = np.empty(0, dtype=np.int64)
            new.build_time_s = time.perf_counter() - t0
            return new
        sat = np.zeros((changed.shape[0] + 1, changed.shape[1] + 1), dtype=np.int32)
        np.cumsum(np.cumsum(changed, axis=0, dtype=np.int32), axis=1, out=sat[1:, 1:])
        band = reweight_band(sat, self.stride_cells, self._offset, self._ni, self._nj, UNIT_HALF)
        if band is None:  # no move reaches a changed cell
            new.edges_computed = 0
            new.changed_moves = np.empty(0, dtype=np.int64)
            new.build_time_s = time.perf_counter() - t0
            return new
        # the moves scanned start in node rows i0:i1 and end by row i1 + 1: one slice of the edges
        lo = int(self._indptr[band[0] * self._nj])
        hi = int(self._indptr[min(self._ni, band[1] + 2) * self._nj])
        if hi - lo > self.n_edges // 2:  # most of the weights: copy them all, and hold a whole array
            lo, hi = 0, self.n_edges
        values = self._energy_slice(lo, hi)
        arr = cost.arrays
        recomputed, flips, new.changed_moves = lattice_reweight(
            arr.cells, arr.grade_table, arr.geo, self.stride_cells, self._offset, self._ni, self._nj,
            UNIT_HALF, sat, self._pos, values, band, lo,
        )
        if int(flips.sum()):
            w = lattice_weights(arr.cells, arr.grade_table, arr.geo, self.stride_cells, self._offset,
                                self._ni, self._nj, UNIT_HALF)
            new._set_structure(w)
            new.edges_computed = int(w.size - np.count_nonzero(self._out_of_grid_mask()))
        else:
            new._energy = self._patched(lo, values)
            new.edges_computed = int(recomputed.sum())
        new.build_time_s = time.perf_counter() - t0
        return new

    def _patched(self, lo: int, values: np.ndarray) -> np.ndarray | tuple:
        """This lattice's energy weights with ``[lo, lo + values.size)`` replaced: the slice on top
        of the same base (no copy), or a whole array once the slices cover half the edges."""
        e = self._energy
        base, patches = e if isinstance(e, tuple) else (e, ())
        if lo == 0 and values.size == self.n_edges:
            return values
        patches = patches + ((lo, values),)
        if sum(v.size for _, v in patches) <= self.n_edges // 2:
            return base, patches
        whole = base.copy()
        for plo, v in patches:
            whole[plo:plo + v.size] = v
        return whole

    def changed_moves_since(self, other: Lattice) -> np.ndarray:
        """Ids (``node * 16 + k``) of the moves whose energy differs between ``other`` and this lattice.

        :attr:`changed_moves` when this lattice was refreshed from ``other`` (no work);
        otherwise both lattices' move energies are compared (one pass over every move).

        Parameters
        ----------
        other : Lattice
            A lattice over the same node grid (e.g. an earlier version of this one).

        Returns
        -------
        ndarray of int64
            Ascending move ids; empty when ``other`` is this lattice.

        Raises
        ------
        InvalidParameterError
            ``other`` not a lattice over the same map grid, stride and node grid.
        """
        if not isinstance(other, Lattice):
            raise InvalidParameterError(f"other must be a Lattice, got {type(other).__name__!r}")
        if other is self or other._token is self._token:
            return np.empty(0, dtype=np.int64)
        if self._refreshed_from is other._token:
            return self.changed_moves
        if (other.stride_cells, other._ni, other._nj) != (self.stride_cells, self._ni, self._nj) or not (
            other.cost.terrain is self.cost.terrain or other.cost.terrain.same_grid(self.cost.terrain)
        ):
            raise InvalidParameterError(
                f"other must be a lattice over the same grid and node grid ({self._ni} x {self._nj} nodes at "
                f"stride_cells={self.stride_cells}), got {other._ni} x {other._nj} at stride_cells={other.stride_cells}"
            )
        return np.flatnonzero(self.move_energies_j().ravel() != other.move_energies_j().ravel())

    def move_energies_j(self, moves: np.ndarray | None = None) -> np.ndarray:
        """Drive energies (J) of lattice moves; ``inf`` for a move that is not an edge.

        Parameters
        ----------
        moves : ndarray of int, optional
            Move ids ``node * 16 + k`` (``k`` indexing :data:`LATTICE_OFFSETS`); default all.

        Returns
        -------
        ndarray of float
            The energies of ``moves``, or of every move as a ``(n_nodes, 16)`` array.
        """
        pos = self._pos.ravel() if moves is None else self._pos.ravel()[np.asarray(moves, dtype=np.int64)]
        out = np.full(pos.shape, np.inf)
        ok = pos >= 0
        e = self._energy
        if moves is None or not isinstance(e, tuple):
            out[ok] = self._energy_data()[pos[ok]]
        else:  # a few moves of a refreshed lattice: read through its slices
            base, patches = e
            q = pos[ok]
            values = base[q]
            for lo, v in patches:
                inside = (q >= lo) & (q < lo + v.size)
                values[inside] = v[q[inside] - lo]
            out[ok] = values
        return out.reshape(self._pos.shape) if moves is None else out

    @classmethod
    def for_cost(cls, cost: EnergyCost, stride_cells: int = 1) -> Lattice:
        """The lattice of ``cost`` at ``stride_cells``, built once and cached on the cost."""
        key = check_int("stride_cells", stride_cells, low=1)
        lat = cost.lattices.get(key)
        if lat is None:
            lat = cls(cost, stride_cells)
            cost.lattices[key] = lat
        return lat

    def graph(self, weight: str = "energy") -> csr_matrix:
        """The directed lattice graph as a sparse matrix (a copy): entry ``[u, v]`` is the weight
        of move ``u -> v`` (drive energy in J, or length in m); absent moves are not stored.

        Raises
        ------
        UnknownNameError
            Unknown ``weight``.
        """
        if weight not in LATTICE_WEIGHTS:
            raise UnknownNameError(f"weight must be one of {LATTICE_WEIGHTS!r}, got {weight!r}")
        n = self.n_nodes
        return csr_matrix((self._weights(weight).copy(), self._indices.copy(), self._indptr.copy()), shape=(n, n))

    @property
    def n_nodes(self) -> int:
        """Number of lattice nodes."""
        return self._ni * self._nj

    def node_xy(self, node: np.ndarray) -> np.ndarray:
        """World coordinates (m) of node indices, shape (N, 2)."""
        node = np.asarray(node, dtype=np.int64)
        return np.column_stack([self._node_x[node % self._nj], self._node_y[node // self._nj]])

    def _nearby_nodes(self, p: np.ndarray) -> np.ndarray:
        """Nodes within 1.5 strides of a point."""
        d = self.cost.terrain.cell_size_m * self.stride_cells
        radius = 1.5 * d
        cols = np.flatnonzero(np.abs(self._node_x - p[0]) <= radius)
        rows = np.flatnonzero(np.abs(self._node_y - p[1]) <= radius)
        nodes = (rows[:, None] * self._nj + cols[None, :]).ravel()
        xy = self.node_xy(nodes)
        return nodes[np.hypot(xy[:, 0] - p[0], xy[:, 1] - p[1]) <= radius]

    def joins(
        self, xy_m: np.ndarray, *, to_point: bool = False, weight: str = "energy"
    ) -> tuple[np.ndarray, np.ndarray]:
        """The lattice nodes a query point is joined to, and the weights of the joining segments.

        Parameters
        ----------
        xy_m : ndarray, shape (2,)
            A point on the map (m), already checked.
        to_point : bool
            False: segments from the point to the nodes (a start); True: from the nodes to
            the point (a goal).
        weight : {"energy", "length"}

        Returns
        -------
        nodes : ndarray of int64
            Nodes within 1.5 strides whose joining segment is drivable.
        weights : ndarray of float
            Drive energy (J) or length (m) of each joining segment.
        """
        p = np.asarray(xy_m, dtype=np.float64)
        nodes = self._nearby_nodes(p)
        xy = self.node_xy(nodes)
        ends = np.broadcast_to(p, xy.shape)
        e = self.cost.segment_energy_j(xy, ends) if to_point else self.cost.segment_energy_j(ends, xy)
        if weight == "length":
            e = np.where(np.isfinite(e), np.hypot(*(xy - p).T), np.inf)
        ok = np.isfinite(e)
        return nodes[ok].astype(np.int64), e[ok]

    def path_via(self, start_xy_m: np.ndarray, nodes: list[int] | np.ndarray, goal_xy_m: np.ndarray,
                 objective: float, weight: str = "energy", solve_time_s: float = 0.0) -> LatticePath:
        """The :class:`LatticePath` of the route ``start, nodes..., goal`` (collinear runs merged);
        not found when ``objective`` is not finite."""
        if not math.isfinite(objective):
            return LatticePath(False, np.empty((0, 2)), math.inf, weight, solve_time_s)
        nodes = np.asarray(nodes, dtype=np.int64)
        mid = self.node_xy(nodes) if nodes.size else np.empty((0, 2))
        waypoints = _merge_collinear(np.vstack([start_xy_m, mid, goal_xy_m]))
        return LatticePath(True, waypoints, float(objective), weight, solve_time_s)

    def shortest_path(
        self,
        start_xy_m: tuple[float, float],
        goal_xy_m: tuple[float, float],
        weight: str = "energy",
    ) -> LatticePath:
        """Best lattice route from start to goal.

        Parameters
        ----------
        start_xy_m, goal_xy_m : (float, float)
            Points on the map (m).
        weight : {"energy", "length"}
            Minimise drive energy (J) or length (m).

        Returns
        -------
        LatticePath
            ``found=False`` when no lattice route exists (e.g. the points are separated by
            obstacles, or a passage is narrower than the lattice can thread).

        Raises
        ------
        UnknownNameError
            Unknown ``weight``.
        InvalidParameterError, OutOfBoundsError
            NaN points / points outside the map.
        """
        t0 = time.perf_counter()
        if weight not in LATTICE_WEIGHTS:
            raise UnknownNameError(f"weight must be one of {LATTICE_WEIGHTS!r}, got {weight!r}")
        pts = as_points([start_xy_m, goal_xy_m], "start/goal")
        self.cost.check_inside(pts, "start/goal")
        start, goal = pts
        cost = self.cost
        src, e_src = self.joins(start, weight=weight)
        dst, e_dst = self.joins(goal, to_point=True, weight=weight)
        e_direct = float(cost.segment_energy_j(start, goal)[0])
        if weight == "length":
            e_direct = float(np.hypot(*(goal - start))) if math.isfinite(e_direct) else math.inf
        best = e_direct
        best_nodes: list[int] = []
        if src.size and dst.size:
            h_per_m = cost.min_energy_per_metre_j if weight == "energy" else 1.0
            total, last, pred = astar(
                self._indptr, self._indices, self._weights(weight), self._node_x, self._node_y, self._nj,
                src, e_src, dst, e_dst, float(goal[0]), float(goal[1]), float(h_per_m), best,
            )
            if last >= 0 and total < best:
                best = float(total)
                chain = []
                node = int(last)
                while node >= 0:
                    chain.append(node)
                    node = int(pred[node])
                best_nodes = chain[::-1]
        path = self.path_via(start, best_nodes, goal, best, weight)
        return dataclasses.replace(path, solve_time_s=time.perf_counter() - t0)

    def _from_source(self, src: np.ndarray, e_src: np.ndarray, weight: str) -> tuple[np.ndarray, np.ndarray]:
        """scipy's Dijkstra from a virtual source joined to the nodes ``src`` at ``e_src``: (dist, pred) of every node."""
        n = self.n_nodes
        data = np.concatenate([self._weights(weight), e_src])
        indices = np.concatenate([self._indices, src.astype(np.int32)])
        indptr = np.append(self._indptr, np.int32(self._indptr[-1] + src.size))
        graph = csr_matrix((data, indices, indptr), shape=(n + 1, n + 1))
        return dijkstra(graph, directed=True, indices=n, return_predecessors=True)

    def _best_exit(self, dist: np.ndarray, pred: np.ndarray, dst: np.ndarray, e_dst: np.ndarray,
                   best: float) -> tuple[float, list[int]]:
        """The cheapest way out through the nodes ``dst`` (at ``e_dst``) if it beats ``best``: (energy, node chain)."""
        total = dist[dst] + e_dst
        k = int(np.argmin(total))
        if not total[k] < best:
            return best, []
        chain, node = [], int(dst[k])
        while node != self.n_nodes and node >= 0:
            chain.append(node)
            node = int(pred[node])
        return float(total[k]), chain[::-1]


    def paths_from(self, start_xy_m: tuple[float, float], goals_xy_m: object,
                   weight: str = "energy") -> list[LatticePath]:
        """Best lattice routes from one start to many goals: one Dijkstra over the whole lattice.

        Each answer equals :meth:`shortest_path` ``(start, goal, weight)`` in objective (ties may
        pick another route of the same weight): the start joins its nodes, one single-source
        search labels every node, and each goal takes its best joining node (or the direct
        segment). Pricing every ordered pair of ``N`` sites costs ``N`` searches, not ``N**2``.

        Parameters
        ----------
        start_xy_m : (float, float)
            The start (m).
        goals_xy_m : array_like, shape (M, 2)
            The goals (m).
        weight : {"energy", "length"}

        Returns
        -------
        list of LatticePath
            One per goal, in order (``found=False`` where the lattice joins none).

        Raises
        ------
        UnknownNameError
            Unknown ``weight``.
        InvalidParameterError, OutOfBoundsError
            NaN points / points outside the map.
        """
        t0 = time.perf_counter()
        if weight not in LATTICE_WEIGHTS:
            raise UnknownNameError(f"weight must be one of {LATTICE_WEIGHTS!r}, got {weight!r}")
        start = as_points([start_xy_m], "start")[0]
        goals = as_points(goals_xy_m, "goals_xy_m")
        self.cost.check_inside(np.vstack([start, goals]), "start/goals")
        src, e_src = self.joins(start, weight=weight)
        searched = self._from_source(src, e_src, weight) if src.size else None
        direct = self.cost.segment_energy_j(np.broadcast_to(start, goals.shape), goals)
        if weight == "length":
            direct = np.where(np.isfinite(direct), np.hypot(*(goals - start).T), np.inf)
        out = []
        for goal, best in zip(goals, direct.tolist()):
            nodes: list[int] = []
            if searched is not None:
                dst, e_dst = self.joins(goal, to_point=True, weight=weight)
                if dst.size:
                    best, nodes = self._best_exit(*searched, dst, e_dst, best)
            out.append(self.path_via(start, nodes, goal, best, weight))
        elapsed = time.perf_counter() - t0
        return [dataclasses.replace(p, solve_time_s=elapsed) for p in out]


def _merge_collinear(pts: np.ndarray) -> np.ndarray:
    """Drop interior vertices where the polyline goes straight on (and repeated points)."""
    if pts.shape[0] < 3:
        return pts
    seg = np.diff(pts, axis=0)
    nonzero = np.hypot(seg[:, 0], seg[:, 1]) > 0
    pts = np.vstack([pts[:1], pts[1:][nonzero]])
    if pts.shape[0] < 3:
        return pts
    seg = np.diff(pts, axis=0)
    cross = seg[:-1, 0] * seg[1:, 1] - seg[:-1, 1] * seg[1:, 0]
    dot = np.einsum("ij,ij->i", seg[:-1], seg[1:])
    scale = np.hypot(seg[:-1, 0], seg[:-1, 1]) * np.hypot(seg[1:, 0], seg[1:, 1])
    straight = (np.abs(cross) <= 1e-12 * scale) & (dot > 0)
    keep = np.concatenate([[True], ~straight, [True]])
    return pts[keep]
