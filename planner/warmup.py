"""warm_up_kernels: compile (or load from numba's cache) every kernel of the planner before timing anything."""

from __future__ import annotations

import time

import numpy as np

from terrain import TerrainMap

from .anyangle import warm_up_anyangle
from .edge_cost import EnergyCost
from .heading_lattice import heading_cost_to_go, heading_shortest_path, lower_cost_to_go
from .kernels import graph, point_free, walk
from .kernels.corridor import corridor_weights_parallel, corridor_weights_serial
from .lattice import LATTICE_OFFSETS, Lattice
from .reachability import warm_up_reachability
from .refine import relax_path, string_pull
from .replan import IncrementalPlanner
from .tables import CostTables

__all__ = ["warm_up_kernels"]


def warm_up_kernels() -> float:
    """Compile (or load from numba's on-disk cache) every compiled kernel of the planner.

    Runs each kernel once on a tiny map with the same argument types as real use — the
    serial and the parallel variant of each parallel kernel — so that neither map
    preparation nor planning times include compilation.

    Returns
    -------
    float
        Seconds spent; the first call in a fresh environment compiles (tens of seconds on a
        slow machine), later processes load the cached machine code (well under a second).
    """
    t0 = time.perf_counter()
    tmap = TerrainMap(np.zeros((4, 4)), 1.0)
    cost = EnergyCost(tmap, np.zeros((4, 4), np.int32), CostTables(np.ones((1, 3)), np.ones((1, 2))),
                      speed_mps=1.0, battery_voltage_v=1.0, turn_rate_radps=1.0)
    arr = cost.arrays
    xs = np.array([0.5, 1.5])
    ys = np.array([0.5, 2.5])
    for kernel in (walk.walk_many_serial, walk.walk_many_parallel):
        kernel(arr.cells, arr.grade_table, arr.geo, xs, ys, ys, xs)
    cost.segment_energy_one_j(0.5, 0.5, 3.5, 2.5)
    relax_path(cost, [[0.5, 0.5], [2.0, 3.0], [3.5, 0.5]])
    point_free(arr.cells, arr.geo, 0.5, 0.5)
    half = np.array([(0, 1), (1, 0)], dtype=np.int64)
    for kernel in (graph.lattice_weights_serial, graph.lattice_weights_parallel):
        kernel(arr.cells, arr.grade_table, arr.geo, 1, 0, 4, 4, half)
    sat = np.zeros((5, 5), dtype=np.int32)
    pos = np.full((16, 4), -1, dtype=np.int32)
    data = np.zeros(0)
    for kernel in (graph.lattice_reweight_serial, graph.lattice_reweight_parallel):
        kernel(arr.cells, arr.grade_table, arr.geo, 1, 0, 4, 4, half, sat, pos, data)
    rows, cols = (a.astype(np.int64) for a in np.nonzero(np.ones((4, 4), dtype=bool)))
    index = np.arange(16, dtype=np.int32).reshape(4, 4)
    for kernel in (corridor_weights_serial, corridor_weights_parallel):  # coarse-to-fine's corridor graph
        kernel(arr.cells, arr.grade_table, arr.geo, rows, cols, index, LATTICE_OFFSETS[:8])
    lattice = Lattice.for_cost(cost, 1)
    path = lattice.shortest_path((0.5, 0.5), (3.5, 3.5), weight="length")
    heading_shortest_path(lattice, (0.5, 0.5), (3.5, 2.5))  # the heading lattice: cost-to-go, then its A*
    dearer = cost.with_tables(CostTables(2.0 * cost.tables.grade_table_j_per_m, cost.tables.turn_table_j))  # incremental reweighting
    changed = np.zeros((4, 4), dtype=bool)
    changed[1, 1] = True
    refreshed = lattice.refreshed(dearer, changed)
    replanner = IncrementalPlanner(lattice, (3.5, 3.5), heading=False)  # D* Lite: search, then a repair
    replanner.plan((0.5, 0.5))
    replanner.replan((0.5, 0.5), refreshed)
    IncrementalPlanner(lattice, (3.5, 3.5)).plan((0.5, 0.5))  # the heading replanner: its workspace's A*
    # and its heuristic lowered where moves got dearer (a replan on a map this small recomputes it instead)
    h = heading_cost_to_go(lattice, (0.5, 0.5), (3.5, 3.5))
    lower_cost_to_go(h, refreshed, np.arange(4, dtype=np.int64), (3.5, 3.5))
    string_pull(cost, np.vstack([path.waypoints_m, [[0.5, 3.5]]]))
    warm_up_reachability()
    warm_up_anyangle()
    return time.perf_counter() - t0
