"""Compiled (numba) kernels of the planner behind one public seam, over :class:`CostArrays`.

- :mod:`.arrays` — :class:`CostArrays`, the packed read-only arrays of an ``EnergyCost``;
- :mod:`.walk` — cell walks: segment energies, free points, turn energies;
- :mod:`.paths` — whole-polyline kernels: pattern-search relaxation, line-of-sight pulls;
- :mod:`.graph` — lattice graphs: move energies, their refresh, an indexed heap, A*;
- :mod:`.reach` — single-source Dijkstra over a node grid's dense move energies (reachability);
- :mod:`.unit_moves` — the stride-1 lattice's move energies from per-cell direction rates;
- :mod:`.variants` — serial / parallel compilations picked by work size.

Every kernel is compiled with ``cache=True``; ``planner.warm_up_kernels`` compiles or loads
them all.
"""

from .arrays import CostArrays
from .graph import astar, heap_pop, heap_set, lattice_reweight, lattice_weights
from .paths import KEEP_RTOL, relax_polyline, string_pull_indices
from .reach import grid_dijkstra
from .unit_moves import UNIT_HALF, unit_lattice_weights
from .variants import PARALLEL_MIN_WALKS, use_parallel
from .walk import point_free, turn_energy, walk_forward, walk_many, walk_pair

__all__ = [
    "CostArrays",
    "walk_pair",
    "walk_forward",
    "walk_many",
    "point_free",
    "turn_energy",
    "relax_polyline",
    "string_pull_indices",
    "KEEP_RTOL",
    "astar",
    "lattice_weights",
    "lattice_reweight",
    "heap_set",
    "heap_pop",
    "grid_dijkstra",
    "unit_lattice_weights",
    "UNIT_HALF",
    "PARALLEL_MIN_WALKS",
    "use_parallel",
]
