"""Compiled corridor lattice: the 16 directed moves of every 1-cell lattice node inside a corridor of cells."""

from __future__ import annotations

import numba
import numpy as np

from .variants import compile_variants, use_parallel
from .walk import walk_pair

__all__ = ["corridor_weights", "corridor_weights_serial", "corridor_weights_parallel"]


def _corridor_weights(cells, table, geo, node_rows, node_cols, index, half):  # pragma: no cover - compiled
    """Energies ``(n_nodes, 16)`` of the moves between corridor nodes (``inf`` = no edge).

    Node ``u`` sits at the centre of cell ``(node_rows[u], node_cols[u])``; ``index[r, c]`` is
    the node of a cell (``-1`` outside the corridor). Move ``k < 8`` is ``half[k]``, move
    ``k + 8`` its reverse; both directions of a pair are costed in one walk by the node with
    the pair's first offset, so each walk is made once. Moves are the 1-cell lattice's
    (:mod:`planner.lattice`), so the corridor graph is a subgraph of it.
    """
    n = node_rows.size
    nh = half.shape[0]
    w = np.full((n, 2 * nh), np.inf)
    x0 = geo[0]
    y0 = geo[1]
    d = geo[2]
    nr = index.shape[0]
    nc = index.shape[1]
    for u in numba.prange(n):
        r = node_rows[u]
        c = node_cols[u]
        xa = x0 + (c + 0.5) * d
        ya = y0 + (r + 0.5) * d
        for k in range(nh):
            tr = r + half[k, 0]
            tc = c + half[k, 1]
            if tr < 0 or tr >= nr or tc < 0 or tc >= nc:
                continue
            v = index[tr, tc]
            if v < 0:
                continue
            ef, eb = walk_pair(cells, table, geo, xa, ya, x0 + (tc + 0.5) * d, y0 + (tr + 0.5) * d, True)
            w[u, k] = ef
            w[v, nh + k] = eb
    return w


corridor_weights_serial, corridor_weights_parallel = compile_variants(_corridor_weights)


def corridor_weights(cells, table, geo, node_rows, node_cols, index, half):
    """:func:`_corridor_weights`, in parallel when the corridor is large (:func:`use_parallel`)."""
    kernel = corridor_weights_parallel if use_parallel(8 * node_rows.size) else corridor_weights_serial
    return kernel(cells, table, geo, node_rows, node_cols, index, half)
