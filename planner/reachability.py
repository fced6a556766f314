"""Energy reachability: the least energy from a depot to every cell (and back) on the directed lattice.

The graph is the reference lattice of :class:`~planner.Lattice` at stride 1 (a node at
every cell centre, the 16 king and knight moves, each weighted by the cell-walk energy of
its straight segment, uphill ``!=`` downhill; moves that cross a blocked cell or an
undrivable grade are absent), costed with the lattice's own per-metre rates by the stride-1
kernel :func:`~planner.kernels.unit_lattice_weights` (equal to the lattice's
:func:`~planner.kernels.lattice_weights` to rounding, at a third of its work). The depot joins the nodes within 1.5 cells of
it by straight segments, as a lattice query's start does. One single-source Dijkstra
(:func:`~planner.kernels.reach.grid_dijkstra`, compiled) gives every cell's energy *from*
the depot; with ``round_trip`` a second one on the reversed graph gives every cell's
energy *back to* the depot, and the round trip is their sum (both searches run at once on
two threads).

A cell's energy is its lattice node's, so at any cell centre it equals the lattice
planner's optimum between the depot and that point (:meth:`Lattice.shortest_path`) except
where the planner's direct depot-goal segment is cheaper than every lattice route: the
field is that of a robot driving the 16 lattice headings, an upper bound of the straight
line's where that is free.

The move energies of a cost are computed once and kept on the cost (``cost.results``), so
further depots on the same cost only search.
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np

from terrain import TerrainMap
from terrawatt_base.checks import check_bool, check_real
from terrawatt_base.errors import BlockedPositionError, InvalidParameterError

from .edge_cost import EnergyCost
from .kernels import grid_dijkstra, unit_lattice_weights, unit_moves, use_parallel
from .lattice import LATTICE_OFFSETS
from .points import as_points
from .reachability_result import Reachability
from .tables import CostTables

__all__ = ["reachability", "lattice_move_energies", "depot_links", "warm_up_reachability"]

_CACHE_KEY = ("reachability", "lattice_move_energies", 1)
#: Depot links: lattice nodes within this many cells of the depot, as a lattice query's start.
_LINK_RADIUS_CELLS = 1.5


def lattice_move_energies(cost: EnergyCost) -> tuple[np.ndarray, float]:
    """The stride-1 lattice's move energies of ``cost``, ``(rows * cols, 16)`` (J; ``inf``: no move),
    computed once and cached on the cost; returns them with the seconds spent (0 when cached).

    Move ``k`` of node ``r * cols + c`` goes to the node at ``LATTICE_OFFSETS[k]`` from it; the
    weights are those of ``Lattice(cost, stride_cells=1)`` (to rounding), computed by the
    stride-1 kernel :func:`~planner.kernels.unit_lattice_weights`.
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    cached = cost.results.get(_CACHE_KEY)
    if cached is not None:
        return cached, 0.0
    t0 = time.perf_counter()
    rows, cols = cost.shape
    arr = cost.arrays
    w = unit_lattice_weights(arr.cells, arr.grade_table, arr.geo, rows, cols)
    w.setflags(write=False)
    cost.results[_CACHE_KEY] = w
    return w, time.perf_counter() - t0


def warm_up_reachability() -> float:
    """Compile (or load from numba's cache) the reachability kernels: both variants of the stride-1
    move kernel and the Dijkstra, forward and reversed; returns the seconds spent.

    :func:`planner.warm_up_kernels` calls it.
    """
    t0 = time.perf_counter()
    tmap = TerrainMap(np.zeros((4, 4)), 1.0)
    cost = EnergyCost(tmap, np.zeros((4, 4), np.int32), CostTables(np.ones((1, 3)), np.ones((1, 2))),
                      speed_mps=1.0, battery_voltage_v=1.0, turn_rate_radps=1.0)
    arr = cost.arrays
    for kernel in (unit_moves.unit_lattice_weights_serial, unit_moves.unit_lattice_weights_parallel):
        kernel(arr.cells, arr.grade_table, arr.geo, 4, 4, unit_moves.UNIT_HALF, *unit_moves.CROSSINGS, 2)
    reachability(cost, (1.5, 1.5), round_trip=True)
    return time.perf_counter() - t0


def depot_links(cost: EnergyCost, depot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stride-1 lattice nodes within 1.5 cells of a depot ``(x_m, y_m)`` (a checked point on the
    map), and the energies depot -> node and node -> depot (J; ``inf``: no straight drive)."""
    grid = cost.terrain.grid
    radius = _LINK_RADIUS_CELLS * grid.cell_size_m
    xc, yc = cost.terrain.cell_centres()
    cols = np.flatnonzero(np.abs(xc - depot[0]) <= radius)
    rows = np.flatnonzero(np.abs(yc - depot[1]) <= radius)
    rr, cc = np.meshgrid(rows, cols, indexing="ij")
    rr, cc = rr.ravel(), cc.ravel()
    near = np.hypot(xc[cc] - depot[0], yc[rr] - depot[1]) <= radius
    rr, cc = rr[near], cc[near]
    nodes_xy = np.column_stack([xc[cc], yc[rr]])
    out_j = cost.segment_energy_j(np.broadcast_to(depot, nodes_xy.shape), nodes_xy)
    back_j = cost.segment_energy_j(nodes_xy, np.broadcast_to(depot, nodes_xy.shape))
    return (rr * grid.shape[1] + cc).astype(np.int64), out_j, back_j


def reachability(
    cost: EnergyCost,
    depot_xy_m: Any,
    *,
    budget_j: float | None = None,
    reserve_j: float = 0.0,
    round_trip: bool = False,
) -> Reachability:
    """Least energy from a depot to every cell of the map (and back), and the cells within a budget.

    Parameters
    ----------
    cost : EnergyCost
        Edge costs of the map (direction-dependent: uphill costs more than downhill).
    depot_xy_m : (float, float)
        Where the robot starts (and, with ``round_trip``, returns) (m).
    budget_j : float, optional
        Battery energy at the depot (J, > 0), e.g. ``Battery.energy_capacity_j``; ``None``:
        no budget (every cell with a finite energy is reachable).
    reserve_j : float
        Energy that must remain on arrival (J), in ``[0, budget_j)``; a cell is reachable
        when its energy is at most ``budget_j - reserve_j``. For a reserve given as a
        fraction of the battery, pass ``fraction * budget_j``.
    round_trip : bool
        Budget the way out *and back* (forward plus the reversed-graph energy to the depot)
        instead of the way out.

    Returns
    -------
    Reachability
        The energy rasters on the cost's grid (``inf`` where unreachable or blocked), the
        reachable mask, area, farthest distance; ``write`` and ``plot``.

    Raises
    ------
    InvalidParameterError
        ``cost`` not an EnergyCost, NaN depot coordinates, a budget that is not > 0, a
        reserve outside ``[0, budget_j)`` or without a budget, a non-boolean ``round_trip``.
    OutOfBoundsError
        The depot lies outside the map.
    BlockedPositionError
        The depot lies on an obstacle or a cell steeper than the slope limit.

    Examples
    --------
    >>> from terrain import ramp_map
    >>> from planner import EnergyCost
    >>> from planner import CostSpec
    >>> cost = CostSpec().build(ramp_map((20, 40), 1.0, grade=0.05))
    >>> reach = reachability(cost, (20.0, 10.0), round_trip=True)
    >>> bool((reach.round_trip_energy_j >= reach.forward_energy_j).all())
    True
    """
    if not isinstance(cost, EnergyCost):
        raise InvalidParameterError(f"cost must be an EnergyCost, got {type(cost).__name__!r}")
    depot = as_points(depot_xy_m, "depot_xy_m")
    if depot.shape[0] != 1:
        raise InvalidParameterError(f"depot_xy_m must be one point (x_m, y_m), got {depot.shape[0]} points")
    cost.check_inside(depot, "depot")
    depot = depot[0]
    if not bool(cost.is_free(depot)[0]):
        raise BlockedPositionError(
            f"depot {tuple(depot.tolist())!r} m lies on a blocked cell (an obstacle or steeper than "
            f"max_slope_rad={cost.max_slope_rad:.4f}); choose a depot on free ground"
        )
    budget = None if budget_j is None else check_real("budget_j", budget_j, low=0.0, low_inclusive=False)
    reserve = check_real("reserve_j", reserve_j, low=0.0)
    if budget is None and reserve > 0.0:
        raise InvalidParameterError(f"reserve_j={reserve!r} needs a budget_j to be kept from")
    if budget is not None and reserve >= budget:
        raise InvalidParameterError(f"reserve_j must be below budget_j={budget!r} J, got {reserve!r}")
    trip = check_bool("round_trip", round_trip)

    w, graph_s = lattice_move_energies(cost)
    t0 = time.perf_counter()
    rows, cols = cost.shape
    nodes, out_j, back_j = depot_links(cost, depot)
    di = np.ascontiguousarray(LATTICE_OFFSETS[:, 0])
    dj = np.ascontiguousarray(LATTICE_OFFSETS[:, 1])
    ok_out, ok_back = np.isfinite(out_j), np.isfinite(back_j)
    args_out = (w, rows, cols, di, dj, nodes[ok_out], out_j[ok_out], False)
    args_back = (w, rows, cols, di, dj, nodes[ok_back], back_j[ok_back], True)
    if trip and use_parallel(rows * cols):
        with ThreadPoolExecutor(max_workers=2) as pool:  # the kernel releases the GIL
            jobs = [pool.submit(grid_dijkstra, *args_out), pool.submit(grid_dijkstra, *args_back)]
            forward, back = (job.result() for job in jobs)
    else:
        forward = grid_dijkstra(*args_out)
        back = grid_dijkstra(*args_back) if trip else None
    blocked = cost.blocked
    forward = forward.reshape(rows, cols)
    forward[blocked] = np.inf  # already inf (no move enters a blocked cell); said, not assumed
    forward.setflags(write=False)
    total = None
    if back is not None:
        back = back.reshape(rows, cols)
        back[blocked] = np.inf
        back.setflags(write=False)
        total = forward + back
        total.setflags(write=False)
    return Reachability(
        grid=cost.terrain.grid,
        crs=cost.terrain.crs,
        depot_xy_m=(float(depot[0]), float(depot[1])),
        forward_energy_j=forward,
        back_energy_j=back,
        round_trip_energy_j=total,
        blocked=blocked,
        budget_j=budget,
        reserve_j=reserve,
        round_trip=trip,
        graph_time_s=graph_s,
        search_time_s=time.perf_counter() - t0,
    )
